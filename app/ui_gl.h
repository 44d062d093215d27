// The GL side of the panel: ImGui's OpenGL 3 backend (compiled from Debian's example source with
// our glad loader, app/CMakeLists.txt) and the compositor that puts the scene and the panel in one
// frame. The same code serves the window (framebuffer 0) and headless frames (an offscreen target).
//
//   frame (W + P) x H:  [ scene, W x H, the Renderer's resolved image | panel, P x H ]
//   the ImGui draw data covers the whole frame (the panel window and the view overlay).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/renderer.h"

namespace ponyhop {

// ImGui_ImplOpenGL3 for the current ImGui context. Needs a current GL 3.3 context with GL loaded.
class UiGl {
 public:
  UiGl();
  ~UiGl();
  UiGl(const UiGl&) = delete;
  UiGl& operator=(const UiGl&) = delete;

  void newFrame();  // before ImGui::NewFrame()
  // Where a compose's time goes (ms): the clear (none with the panel cache) and the one copy of
  // the scene into the frame, then the panel: ImGui drawn into the same framebuffer over it, or,
  // with the panel cache, the panel's texture redrawn if it changed, copied, and the view's
  // overlay drawn.
  struct Times {
    double copy_ms = 0.0, panel_ms = 0.0;
    bool panel_drawn = true;       // ImGui drew the panel this frame (false: its texture was copied as it was)
    double panel_redraw_ms = 0.0;  // with the panel cache: of panel_ms, ImGui drawing the panel's texture
  };
  // What a compose drew into the target: the view's columns (the scene and its overlay), the
  // panel's columns, both (a frame drawn whole) or neither (nothing changed since the last
  // compose into this target: the target already holds the frame). The window presents these.
  struct Damage {
    bool view = true, panel = true;
    bool any() const { return view || panel; }
  };
  // Into framebuffer `fbo` (width x height): the renderer's last frame in the left scene_width
  // pixels, then ImGui's draw data of the frame just ended (ImGui::Render()) over everything.
  // `scene_new`: the renderer drew a new view since the last compose (false: it holds the view
  // last composed, ViewReuse). With `times`: each step ends with glFinish and is timed (a
  // software rasterizer draws a framebuffer's binned work at its flush, so the time lands in its
  // step). Without the panel cache or the kept target the frame is drawn whole every time.
  Damage compose(const Renderer& renderer, unsigned fbo, int width, int height, int scene_width, Times* times = nullptr,
                 bool scene_new = true);

  // The panel cache (the window turns it on): the panel's columns are drawn by ImGui into a
  // texture of their own only when their draw data differs from the one the texture holds (the
  // vertices, indices and commands, compared whole: no hash to collide), and copied to the frame
  // whenever the frame changed; the view's overlay (ImGui's background list, over the scene) is
  // drawn with the view. So a still panel costs one copy of its columns instead of ImGui's ~2,200
  // blended triangles, and an edit shows in the frame that made it. A frame whose view, overlay
  // and panel are all unchanged is not drawn at all (Damage none). The frame is the same to the
  // byte as without the cache; when a tooltip or popup crosses into the scene view, or the
  // overlay into the panel, that frame is drawn whole without it.
  void setPanelCache(bool on);
  // The kept target (with the panel cache; the window's back buffer when it is presented by
  // rectangle copies, app/window_present.h): the target keeps its pixels from one compose to the
  // next, so only what changed is drawn into it: the view's columns when the view or its overlay
  // changed, the panel's columns (cleared and drawn by ImGui, no texture) when the panel did.
  void setTargetKeeps(bool on);
  // The target's pixels are not known any more (a resize, an expose, something else drew there):
  // the next compose draws the frame whole.
  void forgetTarget() { known_ = false; }
  // Whether the last compose had ImGui draw the panel (false: the cache's texture was copied, or
  // the panel's columns were left as they were).
  bool lastPanelDrawn() const { return last_panel_drawn_; }
  const Damage& lastDamage() const { return last_damage_; }

 private:
  bool composeSaving(const Renderer& renderer, unsigned fbo, int width, int height, int scene_width, bool scene_new,
                     Times* times);

  bool cache_on_ = false, keeps_ = false;
  bool last_panel_drawn_ = true;
  Damage last_damage_;
  unsigned panel_fbo_ = 0, panel_tex_ = 0;
  int panel_w_ = 0, panel_h_ = 0;
  bool panel_valid_ = false;        // the texture (kept target: the target's panel columns) holds panel_sig_
  std::vector<uint8_t> panel_sig_;  // what the panel's columns were drawn from
  std::vector<uint8_t> sig_;        // this frame's, compared with it
  // The target as the last compose left it: the whole frame of that size, its view's overlay
  // drawn from overlay_sig_ (and, with a kept target, its panel from panel_sig_).
  bool known_ = false;
  unsigned known_fbo_ = 0;
  int known_w_ = 0, known_h_ = 0, known_scene_w_ = 0;
  std::vector<uint8_t> overlay_sig_, overlay_now_;
};

// An RGBA8 framebuffer for headless frames with the panel.
class OffscreenTarget {
 public:
  OffscreenTarget(int width, int height);
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  unsigned fbo() const { return fbo_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // RGBA8 rows, top row first.
  void readPixels(std::vector<uint8_t>& rgba) const;

 private:
  unsigned fbo_ = 0, color_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace ponyhop

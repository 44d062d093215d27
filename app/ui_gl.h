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
  // Into framebuffer `fbo` (width x height): the renderer's last frame in the left scene_width
  // pixels, then ImGui's draw data of the frame just ended (ImGui::Render()) over everything.
  // With `times`: each step ends with glFinish and is timed (a software rasterizer draws a
  // framebuffer's binned work at its flush, so the time lands in its step).
  void compose(const Renderer& renderer, unsigned fbo, int width, int height, int scene_width, Times* times = nullptr);

  // The panel cache (the window turns it on): the panel's columns are drawn by ImGui into a
  // texture of their own only when their draw data differs from the one the texture holds (the
  // vertices, indices and commands, compared whole: no hash to collide), and copied to the frame
  // every frame; the view's overlay (ImGui's background list, over the scene) is drawn every
  // frame. So a still panel costs one copy of its columns instead of ImGui's ~2,200 blended
  // triangles, and an edit shows in the frame that made it. The frame is the same to the byte as
  // without the cache; when a tooltip or popup crosses into the scene view, or the overlay into
  // the panel, that frame is drawn without it.
  void setPanelCache(bool on);
  // Whether the last compose had ImGui draw the panel (false: the cache's texture was copied).
  bool lastPanelDrawn() const { return last_panel_drawn_; }

 private:
  bool composeCached(const Renderer& renderer, unsigned fbo, int width, int height, int scene_width, Times* times);

  bool cache_on_ = false;
  bool last_panel_drawn_ = true;
  unsigned panel_fbo_ = 0, panel_tex_ = 0;
  int panel_w_ = 0, panel_h_ = 0;
  bool panel_valid_ = false;        // the texture holds the draw data in panel_sig_
  std::vector<uint8_t> panel_sig_;  // what the texture was drawn from
  std::vector<uint8_t> sig_;        // this frame's, compared with it
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

// The tuning panel without a window: an OSMesa context, the renderer, the panel and the
// compositor, driven one frame at a time with synthetic input. `ponyhop render --ui` writes its
// frames with it; tests click and drag the panel through it.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "app/panel.h"
#include "app/ui_gl.h"
#include "app/ui_sim.h"
#include "engine/gl_context.h"
#include "engine/renderer.h"

namespace ponyhop {

// A still final view whose inputs did not change is not rendered again: the renderer's output
// still holds it, and the compositor copies it to the screen as it would a new one. The inputs
// are the simulation's change counter (edits, live ones too, steps, playback, reset, load), the
// camera, the view's size and the quality. Draft views are always rendered (something moves; a
// pull's spring is drawn from the mouse), and so is the first final view after them.
class ViewReuse {
 public:
  // Renders the view unless it is the same final view as the last one rendered; true when it
  // rendered.
  bool render(Renderer& renderer, LiveSim& sim, const Camera& camera, int width, int height, RenderQuality quality,
              double draft_scale = 1.0);
  void forget() { valid_ = false; }  // the next view renders (the renderer drew something else)

 private:
  struct Key {
    uint64_t changes = 0;
    double sim_time = 0.0;
    Camera camera;
    int width = 0, height = 0;
    bool operator==(const Key& o) const;
  };
  Key last_;
  bool valid_ = false;  // last_ is a final view the renderer's output still holds
};

class HeadlessUi {
 public:
  // The scene view is scene_width x height, the panel panel_width x height beside it.
  // Throws InputError for a scene that cannot be built, std::runtime_error without GL.
  HeadlessUi(const Scene& scene, int scene_width, int height, int panel_width = Panel::kDefaultWidth);
  ~HeadlessUi();

  // One frame: feeds `in` (its width/height are replaced by the frame's), builds the panel
  // (which advances playback by in.dt), renders the scene and composes the frame. With
  // `sim_time`, the simulation is stepped to exactly that time instead (video frames), and
  // playback does not advance. Pixels (RGBA8, top row first) when rgba is given.
  void frame(const UiInput& in, std::vector<uint8_t>* rgba = nullptr, std::optional<double> sim_time = {});

  // The window's two savings, off by default (`render --ui` and the snapshots draw every frame in
  // full): a still final view is re-presented instead of rendered again (ViewReuse), and the panel
  // is drawn into its own texture only when it changed (UiGl::setPanelCache). Tests turn them on
  // to check that a frame made with them is the frame made without. `target_keeps`: the offscreen
  // target is drawn as the window's back buffer is when it is presented by rectangle copies
  // (UiGl::setTargetKeeps: only what changed is drawn into it), else as when it is swapped.
  void setWindowSavings(bool on, bool target_keeps = false);
  // What the last frame drew into the target (with the savings: possibly nothing).
  UiGl::Damage lastDamage() const { return gl_->lastDamage(); }
  // The target the frames are composed into, and telling the compositor that its pixels are not
  // known any more (tests draw over it, as an expose or a resize would lose the window's).
  unsigned targetFbo() const { return target_->fbo(); }
  void forgetTarget() { gl_->forgetTarget(); }
  // Whether the last frame rendered the scene (false: the last final view, re-presented).
  bool lastViewRendered() const { return last_rendered_; }
  // Whether the last frame's panel was drawn by ImGui (false: the panel cache's texture, copied).
  bool lastPanelDrawn() const { return gl_->lastPanelDrawn(); }

  int width() const { return layout_.width; }
  int height() const { return layout_.height; }
  const PanelLayout& layout() const { return layout_; }
  LiveSim& sim() { return *sim_; }
  Panel& panel() { return *panel_; }
  Renderer& renderer() { return *renderer_; }

 private:
  PanelLayout layout_;
  std::unique_ptr<HeadlessContext> context_;
  std::unique_ptr<PanelContext> imgui_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<UiGl> gl_;
  std::unique_ptr<OffscreenTarget> target_;
  std::unique_ptr<LiveSim> sim_;
  std::unique_ptr<Panel> panel_;
  bool savings_ = false;
  ViewReuse reuse_;
  bool last_rendered_ = true;
};

// The quality the scene view needs now (call between ImGui::NewFrame and ImGui::Render): draft
// while something moves (the simulation plays, a widget is held or edited, a mouse button is down
// or the wheel turns: orbit, pan, zoom, pull), final once everything is still, so a drag stays
// interactive on a software rasterizer and the still picture refines. A scene set to draft stays draft.
RenderQuality viewQuality(const LiveSim& sim);

// Draws the scene view of one frame: the applied scene's light and look, at the given size and
// quality; records the quality and the pass times in sim.readouts(). A draft frame is rendered at
// draft_scale times the size in each direction (the window's draft at half: a quarter of the
// pixels, which is what a software rasterizer pays for), and the compositor's blit scales it up.
void renderSceneView(Renderer& renderer, LiveSim& sim, const Camera& camera, int width, int height,
                     RenderQuality quality, double draft_scale = 1.0);

}  // namespace ponyhop

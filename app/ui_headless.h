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

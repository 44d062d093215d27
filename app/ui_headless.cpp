#include "app/ui_headless.h"

#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "physics/stage_times.h"

namespace ponyhop {

RenderQuality viewQuality(const LiveSim& sim) {
  if (sim.applied().render.quality == RenderQuality::Draft) return RenderQuality::Draft;
  const ImGuiIO& io = ImGui::GetIO();
  const bool mouse = io.MouseDown[0] || io.MouseDown[1] || io.MouseDown[2] || io.MouseWheel != 0.0f;
  const bool moving = (sim.running() && sim.ok()) || ImGui::IsAnyItemActive() || mouse;
  return moving ? RenderQuality::Draft : RenderQuality::Final;
}

void renderSceneView(Renderer& renderer, LiveSim& sim, const Camera& camera, int width, int height,
                     RenderQuality quality, double draft_scale) {
  RenderParams rp = sim.applied().render;
  const double scale = quality == RenderQuality::Draft ? std::clamp(draft_scale, 0.1, 1.0) : 1.0;
  rp.width = std::max(int(std::lround(width * scale)), 1);
  rp.height = std::max(int(std::lround(height * scale)), 1);
  rp.quality = quality;
  renderer.beginFrame(camera, sim.applied().light, rp);
  sim.draw(renderer, quality == RenderQuality::Draft);
  renderer.endFrame();
  Readouts& r = sim.readouts();
  const RenderStats& st = renderer.stats();
  r.view_draft = st.draft;
  r.shadow_ms = st.shadow_ms;
  r.main_ms = st.main_ms;
  r.aa_ms = st.resolve_ms;
}

bool ViewReuse::Key::operator==(const Key& o) const {
  return changes == o.changes && sim_time == o.sim_time && camera.eye == o.camera.eye &&
         camera.target == o.camera.target && camera.up == o.camera.up && camera.fov == o.camera.fov &&
         camera.znear == o.camera.znear && camera.zfar == o.camera.zfar && width == o.width && height == o.height;
}

bool ViewReuse::render(Renderer& renderer, LiveSim& sim, const Camera& camera, int width, int height,
                       RenderQuality quality, double draft_scale) {
  const Key key{sim.changes(), sim.simTime(), camera, width, height};
  const bool final_view = quality == RenderQuality::Final;
  if (final_view && valid_ && key == last_) return false;
  renderSceneView(renderer, sim, camera, width, height, quality, draft_scale);
  last_ = key;
  valid_ = final_view;
  return true;
}

HeadlessUi::HeadlessUi(const Scene& scene, int scene_width, int height, int panel_width) {
  layout_.width = scene_width + panel_width;
  layout_.height = height;
  layout_.panel_width = panel_width;
  sim_ = std::make_unique<LiveSim>(scene);  // a bad scene fails before any GL is made
  std::string err;
  context_ = HeadlessContext::create(layout_.width, layout_.height, &err);
  if (!context_) throw std::runtime_error("cannot create the headless GL context: " + err);
  renderer_ = std::make_unique<Renderer>();
  if (!renderer_->init(&err)) throw std::runtime_error("renderer: " + err);
  imgui_ = std::make_unique<PanelContext>();
  gl_ = std::make_unique<UiGl>();
  target_ = std::make_unique<OffscreenTarget>(layout_.width, layout_.height);
  sim_->setStepBudgetMs(0.0);  // deterministic: every step is taken, however long it takes
  panel_ = std::make_unique<Panel>(*sim_);
}

HeadlessUi::~HeadlessUi() {
  if (context_) context_->makeCurrent();
  // GL objects go while the context lives; the ImGui context after its backend.
  panel_.reset();
  gl_.reset();
  target_.reset();
  sim_.reset();
  renderer_.reset();
  imgui_.reset();
}

void HeadlessUi::setWindowSavings(bool on, bool target_keeps) {
  savings_ = on;
  reuse_.forget();
  gl_->setPanelCache(on);
  gl_->setTargetKeeps(on && target_keeps);
}

void HeadlessUi::frame(const UiInput& in_raw, std::vector<uint8_t>* rgba, std::optional<double> sim_time) {
  UiInput in = in_raw;
  in.width = float(layout_.width);
  in.height = float(layout_.height);
  if (sim_time) {
    sim_->advanceTo(*sim_time);
  }
  gl_->newFrame();
  feedInput(in);
  ImGui::NewFrame();
  panel_->build(layout_, !sim_time.has_value());
  // Video frames (sim_time) are rendered at the scene's own quality; interactive frames follow
  // the motion, as in the window.
  const RenderQuality quality = sim_time ? sim_->applied().render.quality : viewQuality(*sim_);
  ImGui::Render();
  const auto t0 = Clock::now();
  if (savings_) {
    last_rendered_ = reuse_.render(*renderer_, *sim_, panel_->camera(), layout_.sceneWidth(), layout_.height, quality);
  } else {
    renderSceneView(*renderer_, *sim_, panel_->camera(), layout_.sceneWidth(), layout_.height, quality);
    last_rendered_ = true;
  }
  gl_->compose(*renderer_, target_->fbo(), layout_.width, layout_.height, layout_.sceneWidth(), nullptr,
               last_rendered_);
  if (rgba) target_->readPixels(*rgba);
  panel_->setRenderMs(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
}

}  // namespace ponyhop

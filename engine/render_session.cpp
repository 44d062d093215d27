#include "engine/render_session.h"

#include <stdexcept>

#include "engine/asset_loader.h"

namespace ponyhop {

Camera sceneCamera(const Scene& scene, const Sim& sim, double t, FollowCamera& follow, double dt) {
  if (scene.camera.mode == CameraMode::Follow) {
    return follow.update(scene.camera, t, sim.followPoint(scene.camera.follow), dt);
  }
  return cameraAt(scene.camera, t);
}

RenderSession::RenderSession(const Scene& scene, bool /*reserve_panel*/) : scene_(scene), sim_(scene, &assimpAssets()) {
  std::string err;
  context_ = HeadlessContext::create(scene_.render.width, scene_.render.height, &err);
  if (!context_) throw std::runtime_error("cannot create the headless GL context: " + err);
  renderer_ = std::make_unique<Renderer>();
  if (!renderer_->init(&err)) throw std::runtime_error("renderer: " + err);
  draw_.upload(sim_, *renderer_);
}

RenderSession::~RenderSession() {
  if (context_) context_->makeCurrent();
  renderer_.reset();  // GL objects go while the context lives
}

void RenderSession::makeCurrent() { context_->makeCurrent(); }

bool RenderSession::simulateTo(double t) { return sim_.advanceTo(t); }

void RenderSession::skipFrame(double t) {
  sceneCamera(scene_, sim_, t, follow_, t - last_t_);
  last_t_ = t;
}

void RenderSession::renderFrame(double t, std::vector<uint8_t>& rgba, unsigned hide) {
  context_->makeCurrent();  // several sessions may take turns on one thread (bench-render)
  const Camera cam = sceneCamera(scene_, sim_, t, follow_, t - last_t_);
  last_t_ = t;
  renderer_->beginFrame(cam, scene_.light, scene_.render);
  draw_.setDraft(scene_.render.quality == RenderQuality::Draft);  // fewer hair strands too
  draw_.draw(sim_, *renderer_, scene_, hide);
  renderer_->endFrame();
  renderer_->readPixels(rgba);
}

}  // namespace ponyhop

// A scene rendered headless: the simulation, an OSMesa context, the renderer and the camera,
// one frame at a time. Used by `ponyhop render`, the snapshot tests and the bench.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/camera.h"
#include "engine/gl_context.h"
#include "engine/renderer.h"
#include "engine/scene_draw.h"
#include "sim/sim.h"

namespace ponyhop {

class RenderSession {
 public:
  // Builds the scene and the GL side. Throws InputError on a bad scene, std::runtime_error when
  // no GL context can be made.
  explicit RenderSession(const Scene& scene, bool reserve_panel = false);
  ~RenderSession();

  // Steps the physics up to time t (s). False when the simulation stopped (status()).
  bool simulateTo(double t);
  // Draws the current state as seen at time t (the camera moves with t) and reads it back;
  // `hide`: SceneDraw::Part bits left out.
  void renderFrame(double t, std::vector<uint8_t>& rgba, unsigned hide = 0);
  // Advances what a rendered frame at time t would (the follow camera) without drawing: a chunk
  // of a sequence (`render --range`) passes the frames before it so that its own match a full run.
  void skipFrame(double t);
  // Makes this session's GL context current. renderFrame does it too; bench-render, whose sessions
  // take turns on one thread, calls it before its clock starts, since a user's single session never
  // switches contexts.
  void makeCurrent();

  const std::string& status() const { return sim_.status(); }
  int width() const { return scene_.render.width; }
  int height() const { return scene_.render.height; }
  Sim& sim() { return sim_; }
  Renderer& renderer() { return *renderer_; }
  const RenderStats& stats() const { return renderer_->stats(); }
  std::string glRenderer() const { return context_->rendererName(); }
  std::string glVersion() const { return context_->version(); }

 private:
  Scene scene_;
  Sim sim_;
  SceneDraw draw_;
  std::unique_ptr<HeadlessContext> context_;
  std::unique_ptr<Renderer> renderer_;
  FollowCamera follow_;
  double last_t_ = 0.0;
};

// The camera for a scene at time t (orbit/fixed are stateless; follow uses `follow`).
Camera sceneCamera(const Scene& scene, const Sim& sim, double t, FollowCamera& follow, double dt);

}  // namespace ponyhop

#include "engine/scene_runtime.h"

#include <cmath>
#include <cstdio>

#include "engine/animation_import.h"
#include "engine/head_fit.h"
#include "engine/scene_io.h"
#include "physics/anchor_motion.h"
#include "physics/keyframes.h"

namespace ponyhop {
namespace {

Eigen::Vector3f toColor(const Eigen::Vector3d& c) { return c.cast<float>(); }

}  // namespace

SceneRuntime::SceneRuntime(const Scene& scene) : scene_(scene), world_(scene.physics) {
  if (!world_.ok()) throw SceneError(scene_.path + ": physics: " + world_.status());
  if (scene_.head) buildHead();
  if (scene_.hopper) buildHopper();
  if (scene_.chain) buildChain();
  if (!world_.ok()) throw SceneError(scene_.path + ": " + world_.status());
}

void SceneRuntime::buildHead() {
  const HeadParams& h = *scene_.head;
  const std::string mesh_path = resolveScenePath(h.mesh, scene_.path);
  std::string err;
  if (mesh_path.empty() || !loadMesh(mesh_path, head_mesh_, &err)) {
    throw SceneError(scene_.path + ": head.mesh: " + (mesh_path.empty() ? h.mesh + ": file not found" : err));
  }
  // The file's own colours (textures, vertex colours, several materials) or head.color.
  for (const std::string& w : head_mesh_.warnings) std::fprintf(stderr, "ponyhop: warning: head.mesh: %s\n", w.c_str());
  if (h.materials == HeadMaterials::Color || (h.materials == HeadMaterials::Auto && !head_mesh_.hasOwnColors())) {
    head_mesh_.dropMaterials();
  }
  const HeadFit fit = fitHead(h, mesh_path, head_mesh_);
  head_mesh_to_body_ = headMeshToBody(h, fit);
  head_anchor_ = head_mesh_to_body_ * headAnchorInMesh(h, fit, head_mesh_);
  head_bounds_centre_ = fit.head_bounds.center().cast<double>();

  // The head's motion: a clip file, the mesh file's own animation, or inline keys.
  const TrackOptions options = trackOptions(h.animation);
  std::optional<KeyframeTrack> track;
  std::string source;
  if (h.animation.clip == "mesh") {
    // The file's own animation, its keys taken as samples of the node's pose (metres, after the
    // same up-axis fix as the mesh).
    source = mesh_path;
    AnimationImportOptions import;
    import.y_up_to_z_up = fit.up == UpAxis::Y;
    track = importAnimationTrack(mesh_path, import, options, &err);
  } else {
    std::vector<Keyframe> keys = h.animation.keys;
    source = "head.animation.keys";
    if (!h.animation.clip.empty()) {
      source = resolveClipPath(h.animation.clip, scene_.path);
      if (source.empty()) throw SceneError(scene_.path + ": head.animation.clip: no clip \"" + h.animation.clip + "\"");
      keys = loadClipFile(source).keys;
    }
    if (keys.empty()) keys.push_back(Keyframe{});  // no animation: the head holds still at the origin
    track = KeyframeTrack::fromKeyframes(keys, options, &err);
  }
  if (!track) throw SceneError(scene_.path + ": head.animation (" + source + "): " + err);
  head_body_ = world_.addKinematicBody(makeMotion(*track), "head");
}

void SceneRuntime::buildChain() {
  const ChainParams& c = *scene_.chain;
  int parent = -1;
  Eigen::Vector3d anchor_local = Eigen::Vector3d::Zero();
  Eigen::Vector3d v0 = Eigen::Vector3d::Zero();
  switch (c.attach) {
    case ChainAttach::Anchor: {
      const AnchorParams& a = *scene_.anchor;
      anchor_body_ = world_.addKinematicBody(anchorMotion(a), "anchor");
      parent = anchor_body_;
      // Constant velocity: the chain starts at rest in the anchor's frame (Galilean invariance).
      if (a.motion == AnchorMotion::ConstantVelocity) v0 = a.velocity;
      break;
    }
    case ChainAttach::Head:
      parent = head_body_;
      anchor_local = head_anchor_;
      if (scene_.head->anchor_space == AnchorSpace::Bounds) anchor_local = standOffAnchor(c);
      break;
    case ChainAttach::Hopper:
      if (!hopper_ || !hopper_->built()) {
        throw SceneError(scene_.path + ": chain.attach: \"hopper\" needs a hopper section");
      }
      // Two-way coupled: the chain hangs from the hopper's body, at the back.
      parent = hopper_->model().body;
      anchor_local = hopper_->backPoint();
      v0 = world_.body(parent).v;
      break;
  }
  chain_ = addChain(world_, c, parent, anchor_local, v0);
}

// An anchor from the head's bounds, moved off the surface as far as the hanging ponytail needs to
// clear the head (engine/head_fit.h).
Eigen::Vector3d SceneRuntime::standOffAnchor(const ChainParams& c) const {
  const RigidBody& head = world_.body(head_body_);
  std::vector<Eigen::Vector3d> points;
  points.reserve(head_mesh_.positions.size());
  for (const auto& p : head_mesh_.positions) points.push_back(head.pointToWorld(head_mesh_to_body_ * p.cast<double>()));
  std::vector<double> radii;
  for (int i = 0; i < c.links; ++i) {
    const double s = c.links > 1 ? double(i) / (c.links - 1) : 0.0;
    radii.push_back(c.radius * (1.0 + (c.taper - 1.0) * s));
  }
  const Eigen::Vector3d centre = head_mesh_to_body_ * head_bounds_centre_;
  const Eigen::Vector3d out = (head_anchor_ - centre).normalized();
  const double push = anchorStandOff(points, head.pointToWorld(head_anchor_), head.q * out, c.direction, c.length, radii);
  return head_anchor_ + push * out;
}

void SceneRuntime::buildHopper() {
  hopper_ = std::make_unique<Hopper>(world_, *scene_.hopper);
  if (!world_.ok()) throw SceneError(scene_.path + ": " + world_.status());
}

bool SceneRuntime::step() {
  if (hopper_) hopper_->think(world_);  // Think once per step, then the step (seed 000)
  world_.step();
  return world_.ok();
}

bool SceneRuntime::advanceTo(double t) {
  const double dt = scene_.physics.dt;
  // Half a step of slack: frame times that are multiples of dt land on a step, not one short.
  while (world_.ok() && world_.time() + 0.5 * dt <= t) step();
  return world_.ok();
}

double SceneRuntime::chainEnergy() const {
  if (!chain_) return 0.0;
  return chain_->kineticEnergy(world_) + chain_->potentialEnergy(world_);
}

Eigen::Vector3d SceneRuntime::followPoint() const {
  const std::string& f = scene_.camera.follow;
  if (f == "chain" && chain_ && !chain_->empty()) return world_.body(chain_->links.front()).x;
  if (hopper_ && (f == "hopper" || (f.empty() && head_body_ < 0))) return world_.body(hopper_->model().body).x;
  if (head_body_ >= 0 && (f.empty() || f == "head")) return world_.body(head_body_).x;
  if (chain_) return chain_->anchor(world_);
  return Eigen::Vector3d::Zero();
}

// The hopper: a rounded body (a fat capsule along x with a cap and two side pods), a ball at the
// hip, the upper leg as a tapered tube and the foot as a thin rod ending in a rubber toe.
void SceneRuntime::drawHopper(Renderer& renderer) const {
  const HopperParams& p = hopper_->params();
  const HopperShape s = hopper_->shape(world_);
  Material paint;
  paint.color = toColor(p.body_color);
  paint.specular = 0.35f;
  paint.shininess = 48.0f;
  Material metal;
  metal.color = toColor(p.leg_color);
  metal.specular = 0.7f;
  metal.shininess = 90.0f;
  Material dark;
  dark.color = {0.18f, 0.19f, 0.21f};
  dark.specular = 0.4f;
  dark.shininess = 60.0f;
  Material rubber;
  rubber.color = toColor(p.foot_color);
  rubber.specular = 0.08f;
  rubber.shininess = 12.0f;

  const Eigen::Vector3d half = 0.5 * p.body_size;
  const auto at = [&](double x, double y, double z) { return Eigen::Vector3d(s.body_x + s.body_q * Eigen::Vector3d(x, y, z)); };
  const double rz = half.z();
  const double ry = 0.75 * half.y();
  // Main hull: a capsule along the body's x axis, squashed look from two overlapping capsules.
  renderer.drawCapsule(at(-(half.x() - rz), 0.0, 0.0), at(half.x() - rz, 0.0, 0.0), rz, paint);
  renderer.drawCapsule(at(-(half.x() - rz) * 0.8, 0.0, 0.15 * rz), at((half.x() - rz) * 0.8, 0.0, 0.15 * rz), 0.9 * rz, paint);
  // Side pods (the body's mass is spread out: its inertia is large) and a sensor dome on top.
  renderer.drawTaperedCapsule(at(-0.55 * half.x(), ry + 0.3 * rz, -0.1 * rz), at(0.35 * half.x(), ry + 0.3 * rz, -0.1 * rz),
                              0.55 * rz, 0.45 * rz, dark);
  renderer.drawTaperedCapsule(at(-0.55 * half.x(), -(ry + 0.3 * rz), -0.1 * rz), at(0.35 * half.x(), -(ry + 0.3 * rz), -0.1 * rz),
                              0.55 * rz, 0.45 * rz, dark);
  renderer.drawSphere(at(0.25 * half.x(), 0.0, 0.85 * rz), 0.45 * rz, metal);
  // Hip ball, upper leg (tube), foot (rod) and toe.
  renderer.drawSphere(s.hip, 1.35 * p.upper_radius, dark);
  renderer.drawTaperedCapsule(s.hip, s.upper_bottom, p.upper_radius, 0.8 * p.upper_radius, metal);
  renderer.drawTaperedCapsule(s.foot_top, s.toe, p.foot_radius, 0.8 * p.foot_radius, metal);
  renderer.drawSphere(s.toe, p.toe_radius, rubber);
}

void SceneRuntime::upload(Renderer& renderer) {
  if (scene_.head && !head_handle_.valid()) head_handle_ = renderer.upload(head_mesh_);
}

void SceneRuntime::draw(Renderer& renderer) const {
  if (hopper_) drawHopper(renderer);
  if (head_body_ >= 0 && head_handle_.valid()) {
    const RigidBody& b = world_.body(head_body_);
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.translate(b.x);
    pose.rotate(b.q);
    Material skin;
    skin.color = head_mesh_.colors.empty() ? toColor(scene_.head->color) : Eigen::Vector3f(1.0f, 1.0f, 1.0f);
    skin.specular = 0.18f;
    skin.shininess = 24.0f;
    renderer.drawMesh(head_handle_, pose * head_mesh_to_body_, skin);
  }
  if (chain_) {
    Material hair;
    hair.color = toColor(scene_.chain->color);
    hair.specular = 0.35f;
    hair.shininess = 60.0f;
    for (const CapsuleSegment& s : chain_->segments(world_)) {
      renderer.drawTaperedCapsule(s.top, s.bottom, s.radius_top, s.radius_bottom, hair);
    }
    if (anchor_body_ >= 0) {
      Material metal;
      metal.color = {0.25f, 0.27f, 0.30f};
      metal.specular = 0.6f;
      metal.shininess = 80.0f;
      renderer.drawSphere(chain_->anchor(world_), 0.8 * chain_->radii.front() + 0.004, metal);
    }
  }
}

}  // namespace ponyhop

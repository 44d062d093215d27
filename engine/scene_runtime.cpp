#include "engine/scene_runtime.h"

#include <cmath>

#include "engine/animation_import.h"
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
  head_mesh_to_body_ = meshToBody(h, head_mesh_.bbox);

  // The head's motion: a clip file, the mesh file's own animation, or inline keys.
  const TrackOptions options = trackOptions(h.animation);
  std::optional<KeyframeTrack> track;
  std::string source;
  if (h.animation.clip == "mesh") {
    // The file's own animation, its keys taken as samples of the node's pose (metres, after the
    // same up-axis fix as the mesh).
    source = mesh_path;
    AnimationImportOptions import;
    import.y_up_to_z_up = h.up_axis == UpAxis::Y;
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
      anchor_local = meshPointToBody(*scene_.head, head_mesh_.bbox, scene_.head->anchor);
      break;
    case ChainAttach::Hopper:
      throw SceneError(scene_.path + ": chain.attach: \"hopper\" needs a hopper section");
  }
  chain_ = addChain(world_, c, parent, anchor_local, v0);
}

bool SceneRuntime::step() {
  world_.step();
  return world_.ok();
}

bool SceneRuntime::advanceTo(double t) {
  const double dt = scene_.physics.dt;
  // Half a step of slack: frame times that are multiples of dt land on a step, not one short.
  while (world_.ok() && world_.time() + 0.5 * dt <= t) world_.step();
  return world_.ok();
}

double SceneRuntime::chainEnergy() const {
  if (!chain_) return 0.0;
  return chain_->kineticEnergy(world_) + chain_->potentialEnergy(world_);
}

Eigen::Vector3d SceneRuntime::followPoint() const {
  const std::string& f = scene_.camera.follow;
  if (f == "chain" && chain_ && !chain_->empty()) return world_.body(chain_->links.front()).x;
  if (head_body_ >= 0 && (f.empty() || f == "head")) return world_.body(head_body_).x;
  if (chain_) return chain_->anchor(world_);
  return Eigen::Vector3d::Zero();
}

void SceneRuntime::upload(Renderer& renderer) {
  if (scene_.head && !head_handle_.valid()) head_handle_ = renderer.upload(head_mesh_);
}

void SceneRuntime::draw(Renderer& renderer) const {
  if (head_body_ >= 0 && head_handle_.valid()) {
    const RigidBody& b = world_.body(head_body_);
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.translate(b.x);
    pose.rotate(b.q);
    Material skin;
    skin.color = toColor(scene_.head->color);
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

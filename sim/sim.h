// A scene made into a simulation: exactly the bodies, joints, controllers and contacts its file
// names, nothing else, and the one place that knows
//   - the step order (World::step: think, forces, joint forces, integrate, stabilize, contact),
//   - the watched points (what the follow camera looks at, what the bench and `sim` track),
//   - state snapshots and carrying state across a rebuild.
// No GL and no file importer: the head's mesh comes through an AssetLoader (engine/ implements it
// with assimp). Drawing a Sim is engine/scene_draw.h's job.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "physics/collisions.h"
#include "physics/models/chain.h"
#include "physics/models/guide.h"
#include "physics/models/hopper.h"
#include "physics/world.h"
#include "sim/assets.h"
#include "sim/scene.h"

namespace ponyhop {

// Everything a step changes, for a later restore into the same Sim (bodies' pose and velocity,
// time, the controllers' own state).
struct SimSnapshot {
  World::SavedState world;  // bodies, time, the controllers' and contacts' own state
};

class Sim {
 public:
  // Builds the world. `assets` reads the head's mesh and the mesh's own animation; a scene with a
  // head needs one. Throws InputError naming the file and the field when something cannot be
  // built (a mesh that does not load, a bad clip, invalid physics).
  explicit Sim(const Scene& scene, const AssetLoader* assets = nullptr);

  // One physics step of dt (World::step: every controller thinks, then the stages). False when
  // the world stopped (status() says when, where and why).
  bool step();
  // Steps (fixed dt, never the frame rate) until the next step would pass t.
  bool advanceTo(double t);

  double time() const { return world_.time(); }
  bool ok() const { return world_.ok(); }
  const std::string& status() const { return world_.status(); }
  const Scene& scene() const { return scene_; }
  World& world() { return world_; }
  const World& world() const { return world_; }
  // The first chain (`chain`, else the first of `chains`), null without any; and every chain in
  // scene order (`chain`, then each of `chains`: chainSection(scene(), i) is the i-th one's section).
  const Chain* chain() const { return chains_.empty() ? nullptr : &chains_.front(); }
  const std::vector<Chain>& chains() const { return chains_; }
  // The chain's guide torques (scene section `guide`, enabled), else null. The goal solve
  // (sim/goal_solve.h) sets its knots between runs.
  GuideTorques* guide() { return guide_.get(); }
  int headBody() const { return head_body_; }
  int anchorBody() const { return anchor_body_; }
  // The head's mesh and placement (null without a head).
  const HeadAsset* head() const { return head_ ? &*head_ : nullptr; }
  // The hoppers, in scene order (`hopper`, then each of `hoppers`).
  const std::vector<std::shared_ptr<Hopper>>& hoppers() const { return hoppers_; }
  const Terrain* terrain() const { return terrain_.get(); }
  const Hopper* hopper(size_t i = 0) const { return i < hoppers_.size() ? hoppers_[i].get() : nullptr; }
  Hopper* hopper(size_t i = 0) { return i < hoppers_.size() ? hoppers_[i].get() : nullptr; }
  // The scene's collisions (collision section), null when it names none.
  const Collisions* collisions() const { return collisions_.get(); }

  // Energy of the first chain (kinetic + gravity, against the chain's hanging-at-rest reference) and
  // the largest joint separation (m).
  double chainEnergy() const;
  double maxJointError() const { return world_.maxJointError(); }

  // The point the follow camera looks at for camera.follow = `follow`: "chain" its first link,
  // "hopper" the (first) hopper's body, "head" the head; "" picks the head, else the hopper, else
  // the chain's anchor, else the origin.
  Eigen::Vector3d followPoint(const std::string& follow) const;
  Eigen::Vector3d followPoint() const { return followPoint(scene_.camera.follow); }
  // The point whose trajectory the bench compares and `sim` reports: the chain's free end, else
  // the first hopper's body centre; and its velocity.
  Eigen::Vector3d trackedPoint() const;
  Eigen::Vector3d trackedVelocity() const;

  // Snapshots: restore(snapshot()) puts this Sim back exactly (bit for bit) where it was.
  SimSnapshot snapshot() const;
  void restore(const SimSnapshot& s);
  // A rebuild that keeps the running state: copies `from`'s body states (pose and velocity) into
  // this freshly built Sim and shifts the prescribed motions by `time_shift` so they continue
  // instead of jumping back to their start. False when the worlds do not match (other bodies,
  // other joints, reduced coordinates) or the copied pose no longer satisfies the joints (an edit
  // moved an attachment): this Sim may then be half changed, build a new one to restart.
  bool carryStateFrom(const Sim& from, double time_shift);

 private:
  void buildHead(const AssetLoader* assets);
  void buildChains();
  void buildChain(const ChainSection& c, const ChainListSection* listed, const std::string& key);
  void buildHoppers();
  void buildJoints();
  void buildServos();
  void buildCollisions();
  Eigen::Vector3d standOffAnchor(const ChainParams& c) const;

  Scene scene_;
  World world_;
  int head_body_ = -1;
  int anchor_body_ = -1;
  std::optional<HeadAsset> head_;
  std::vector<Chain> chains_;
  std::vector<int> scene_joints_;  // the world's joint index of each of the scene's `joints`
  std::shared_ptr<GuideTorques> guide_;
  std::vector<std::shared_ptr<Hopper>> hoppers_;
  std::shared_ptr<Collisions> collisions_;
  std::shared_ptr<const Terrain> terrain_;  // the scene's terrain section (null: the plane z = 0 alone)
};

}  // namespace ponyhop

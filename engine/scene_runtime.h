// What a scene builds: exactly the bodies, joints and drawables its file names, nothing else.
// The physics part needs no GL (used by `ponyhop sim`, the bench, tests); draw() needs a current
// GL context and a Renderer.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

#include "engine/mesh.h"
#include "engine/renderer.h"
#include "engine/scene.h"
#include "physics/chain.h"
#include "physics/hopper.h"
#include "physics/world.h"

namespace ponyhop {

class SceneRuntime {
 public:
  // Builds the world (and loads the head mesh and its clip). Throws SceneError naming the file
  // and the field when something cannot be built (a mesh that does not load, a bad clip).
  explicit SceneRuntime(const Scene& scene);
  // The hopper's contact stage keeps a pointer to world_: a runtime stays where it was built.
  SceneRuntime(const SceneRuntime&) = delete;
  SceneRuntime& operator=(const SceneRuntime&) = delete;

  // Steps the physics (fixed dt, never the frame rate) until the next step would pass t.
  // Returns false when the world stopped (status() says when, where and why).
  bool advanceTo(double t);
  // One physics step (dt): the hopper's Think (when there is a hopper), then World::step().
  // False when the world stopped.
  bool step();

  double time() const { return world_.time(); }
  bool ok() const { return world_.ok(); }
  const std::string& status() const { return world_.status(); }
  const Scene& scene() const { return scene_; }
  World& world() { return world_; }
  const World& world() const { return world_; }
  const Chain* chain() const { return chain_ ? &*chain_ : nullptr; }
  int headBody() const { return head_body_; }
  // The head's mesh as loaded (mesh coordinates) and its placement in the head body's frame.
  const MeshData& headMesh() const { return head_mesh_; }
  const Eigen::Affine3d& headMeshToBody() const { return head_mesh_to_body_; }
  const Eigen::Vector3d& headAnchor() const { return head_anchor_; }  // head body frame
  const Hopper* hopper() const { return hopper_.get(); }
  Hopper* hopper() { return hopper_.get(); }

  // Energy of the chain (kinetic + gravity, against the chain's hanging-at-rest reference) and
  // the largest joint separation (m).
  double chainEnergy() const;
  double maxJointError() const { return world_.maxJointError(); }

  // The point the follow camera looks at: the body named by camera.follow, else the head, the
  // chain's anchor, or the origin.
  Eigen::Vector3d followPoint() const;

  // GL: uploads the meshes (once per renderer) and draws the current state.
  void upload(Renderer& renderer);
  void draw(Renderer& renderer) const;

 private:
  void buildHead();
  void buildChain();
  void buildHopper();
  Eigen::Vector3d standOffAnchor(const ChainParams& c) const;
  void drawHopper(Renderer& renderer) const;

  Scene scene_;
  World world_;
  int head_body_ = -1;
  int anchor_body_ = -1;
  std::optional<Chain> chain_;
  std::unique_ptr<Hopper> hopper_;
  MeshData head_mesh_;
  Eigen::Affine3d head_mesh_to_body_ = Eigen::Affine3d::Identity();
  Eigen::Vector3d head_anchor_ = Eigen::Vector3d::Zero();  // the ponytail's anchor, head body frame
  Eigen::Vector3d head_bounds_centre_ = Eigen::Vector3d::Zero();  // mesh coordinates
  MeshHandle head_handle_;
};

}  // namespace ponyhop

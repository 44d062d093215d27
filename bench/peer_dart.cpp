// The module ponyhop-peer-dart.so, built only when CMake finds DART (libdart-dev; bench/CMakeLists.txt).
//
// A dart::dynamics::Skeleton of BallJoint + BodyNode pairs (reduced coordinates, articulated-body
// forward dynamics), the first joint's parent frame at the anchor, stepped by
// dart::simulation::World (semi-implicit Euler). Body frames are ponyhop's link frames (centre
// of mass at the origin, principal axes); no shapes, so its collision detection finds nothing.
#include <dart/config.hpp>
#include <dart/dynamics/BallJoint.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/simulation/World.hpp>

#include "bench/peer.h"

namespace ponyhop {
namespace {

using dart::dynamics::BallJoint;
using dart::dynamics::BodyNode;

class DartSim final : public PeerSim {
 public:
  DartSim(const PeerChain& chain, double dt) : PeerSim(chain) {
    skeleton_ = dart::dynamics::Skeleton::create("chain");
    BodyNode* parent = nullptr;
    const Eigen::Vector3d half(0.0, 0.0, 0.5 * chain.length);
    for (size_t i = 0; i < chain.mass.size(); ++i) {
      BallJoint::Properties joint;
      joint.mName = "joint" + std::to_string(i);
      // The pivot: the anchor (in the world) or the parent's bottom end; the child's top end.
      joint.mT_ParentBodyToJoint = Eigen::Isometry3d::Identity();
      joint.mT_ParentBodyToJoint.translation() = i == 0 ? chain.anchor : Eigen::Vector3d(-half);
      joint.mT_ChildBodyToJoint = Eigen::Isometry3d::Identity();
      joint.mT_ChildBodyToJoint.translation() = half;
      BodyNode::Properties body;
      body.mName = "link" + std::to_string(i);
      auto [j, b] = skeleton_->createJointAndBodyNodePair<BallJoint>(parent, joint, body);
      b->setInertia(dart::dynamics::Inertia(chain.mass[i], Eigen::Vector3d::Zero(),
                                            Eigen::Matrix3d(chain.inertia[i].asDiagonal())));
      const Eigen::Quaterniond rel = i == 0 ? chain.q[0] : chain.q[i - 1].conjugate() * chain.q[i];
      j->setPositions(BallJoint::convertToPositions(rel.normalized().toRotationMatrix()));
      nodes_.push_back(b);
      parent = b;
    }
    world_ = dart::simulation::World::create();
    world_->setGravity(chain.gravity);
    world_->setTimeStep(dt);
    world_->addSkeleton(skeleton_);
  }

  void step() override { world_->step(); }
  double time() const override { return world_->getTime(); }
  void links(std::vector<PeerLink>& out) override {
    out.resize(nodes_.size());
    for (size_t i = 0; i < nodes_.size(); ++i) {
      const Eigen::Isometry3d& t = nodes_[i]->getWorldTransform();
      out[i].x = t.translation();
      out[i].q = Eigen::Quaterniond(t.linear());
      out[i].v = nodes_[i]->getCOMLinearVelocity();
      out[i].w = nodes_[i]->getAngularVelocity();
    }
  }

 private:
  dart::dynamics::SkeletonPtr skeleton_;
  dart::simulation::WorldPtr world_;
  std::vector<BodyNode*> nodes_;
};

Peer dartPeer() {
  Peer p;
  p.name = "dart/ball";
  p.version = std::string("DART ") + DART_VERSION +
              ": Skeleton of BallJoints, articulated-body dynamics, its semi-implicit Euler, no shapes";
  p.make = [](const PeerChain& chain, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<DartSim>(chain, dt);
  };
  return p;
}

}  // namespace
}  // namespace ponyhop

extern "C" void ponyhop_peers_v1(std::vector<ponyhop::Peer>* out) { out->push_back(ponyhop::dartPeer()); }

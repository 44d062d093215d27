// The module ponyhop-peer-dart.so, built only when CMake finds DART (libdart-dev; bench/CMakeLists.txt).
//
// A dart::dynamics::Skeleton of BallJoint + BodyNode pairs (reduced coordinates, articulated-body
// forward dynamics), the first joint's parent frame at the anchor, stepped by
// dart::simulation::World (semi-implicit Euler). Body frames are ponyhop's link frames (centre
// of mass at the origin, principal axes); no shapes, so its collision detection finds nothing.
//
// A moving anchor (the shake case) is a body on a TranslationalJoint from the world whose actuator
// type is VELOCITY (dart/dynamics/detail/JointAspect.hpp: the command is the joint velocity, the
// joint force is the output): DART takes the joint acceleration (command - velocity) / dt and
// integrates it with its semi-implicit Euler, so the command, set before each step to the secant
// velocity (PeerChain::secant), puts the anchor on the prescribed path at every step's end and
// the chain feels the path's acceleration to second order (a central difference).
#include <dart/config.hpp>
#include <dart/constraint/BallJointConstraint.hpp>
#include <dart/constraint/ConstraintSolver.hpp>
#include <dart/constraint/JointConstraint.hpp>
#include <dart/dynamics/BallJoint.hpp>
#include <dart/dynamics/BodyNode.hpp>
#include <dart/dynamics/RevoluteJoint.hpp>
#include <dart/dynamics/Skeleton.hpp>
#include <dart/dynamics/TranslationalJoint.hpp>
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
    Eigen::Vector3d top = chain.anchor;  // link 0's pivot in its parent's frame (the world's)
    if (chain.moving()) {
      dart::dynamics::TranslationalJoint::Properties joint;
      joint.mName = "anchor";
      joint.mActuatorType = dart::dynamics::Joint::VELOCITY;
      BodyNode::Properties b;
      b.mName = "anchor";
      b.mInertia = dart::dynamics::Inertia(1.0, Eigen::Vector3d::Zero(), 1e-3 * Eigen::Matrix3d::Identity());
      auto [j, body] = skeleton_->createJointAndBodyNodePair<dart::dynamics::TranslationalJoint>(nullptr, joint, b);
      j->setPositions(chain.anchor);
      j->setVelocities(chain.anchorAt(0.0).v);
      anchor_ = j;
      parent = body;
      top.setZero();
    }
    const Eigen::Vector3d half(0.0, 0.0, 0.5 * chain.length);
    for (size_t i = 0; i < chain.mass.size(); ++i) {
      BallJoint::Properties joint;
      joint.mName = "joint" + std::to_string(i);
      // The pivot: the anchor or the parent's bottom end; the child's top end.
      joint.mT_ParentBodyToJoint = Eigen::Isometry3d::Identity();
      joint.mT_ParentBodyToJoint.translation() = i == 0 ? top : Eigen::Vector3d(-half);
      joint.mT_ChildBodyToJoint = Eigen::Isometry3d::Identity();
      joint.mT_ChildBodyToJoint.translation() = half;
      auto [j, b] = skeleton_->createJointAndBodyNodePair<BallJoint>(parent, joint, body(i));
      const Eigen::Quaterniond rel = i == 0 ? chain.q[0] : chain.q[i - 1].conjugate() * chain.q[i];
      j->setPositions(BallJoint::convertToPositions(rel.normalized().toRotationMatrix()));
      // A BallJoint's velocity: the child's angular velocity relative to its parent, child frame.
      j->setVelocities(chain.relativeW0(i));
      nodes_.push_back(b);
      parent = b;
    }
    makeWorld(dt);
  }
  // The four-bar (bench/peer.h): two skeletons (a RevoluteJoint crank with a BallJoint coupler; a
  // RevoluteJoint follower), each hinge's joint frame in its link's t = 0 orientation (angle zero
  // is the t = 0 pose), closed by a BallJointConstraint at the coupler's bottom end.
  DartSim(const PeerFourBar& f, double dt) : PeerSim(f.chain), four_bar_(&f) {
    const PeerChain& c = f.chain;
    const Eigen::Vector3d half(0.0, 0.0, 0.5 * c.length);
    skeleton_ = dart::dynamics::Skeleton::create("crank and coupler");
    BodyNode* crank = hinge(*skeleton_, 0, c.anchor, half, f.axis);
    BallJoint::Properties joint;
    joint.mT_ParentBodyToJoint = Eigen::Isometry3d::Identity();
    joint.mT_ParentBodyToJoint.translation() = -half;
    joint.mT_ChildBodyToJoint = Eigen::Isometry3d::Identity();
    joint.mT_ChildBodyToJoint.translation() = half;
    auto [j, coupler] = skeleton_->createJointAndBodyNodePair<BallJoint>(crank, joint, body(1));
    j->setPositions(BallJoint::convertToPositions((c.q[0].conjugate() * c.q[1]).normalized().toRotationMatrix()));
    nodes_.push_back(coupler);
    follower_ = dart::dynamics::Skeleton::create("follower");
    BodyNode* follower = hinge(*follower_, 2, f.ground, -half, f.axis);
    makeWorld(dt);
    world_->addSkeleton(follower_);
    world_->getConstraintSolver()->addConstraint(std::make_shared<dart::constraint::BallJointConstraint>(
        coupler, follower, coupler->getWorldTransform() * Eigen::Vector3d(-half)));
  }

  void step() override {
    if (four_bar_ && four_bar_->servo()) {
      links(scratch_);
      crank_->setForce(0, four_bar_->servoTorque(scratch_[0], world_->getTime()));  // reset by the step
    }
    if (anchor_) anchor_->setCommands(chain_.secant(world_->getTime(), world_->getTimeStep()));  // reset by the step
    world_->step();
  }
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
  BodyNode::Properties body(size_t i) {
    BodyNode::Properties b;
    b.mName = "link" + std::to_string(i);
    b.mInertia = dart::dynamics::Inertia(chain_.mass[i], Eigen::Vector3d::Zero(),
                                         Eigen::Matrix3d(chain_.inertia[i].asDiagonal()));
    return b;
  }
  // Link i on a RevoluteJoint about `axis` (world) through the world point `pivot`, the pivot at
  // `to_pivot` in the link's frame; the joint frame in the link's t = 0 orientation.
  BodyNode* hinge(dart::dynamics::Skeleton& skeleton, size_t i, const Eigen::Vector3d& pivot,
                  const Eigen::Vector3d& to_pivot, const Eigen::Vector3d& axis) {
    dart::dynamics::RevoluteJoint::Properties joint;
    joint.mT_ParentBodyToJoint = Eigen::Isometry3d::Identity();
    joint.mT_ParentBodyToJoint.linear() = chain_.q[i].normalized().toRotationMatrix();
    joint.mT_ParentBodyToJoint.translation() = pivot;
    joint.mT_ChildBodyToJoint = Eigen::Isometry3d::Identity();
    joint.mT_ChildBodyToJoint.translation() = to_pivot;
    joint.mAxis = chain_.q[i].conjugate() * axis;
    auto [j, b] = skeleton.createJointAndBodyNodePair<dart::dynamics::RevoluteJoint>(nullptr, joint, body(i));
    if (i == 0) crank_ = j;
    nodes_.push_back(b);
    return b;
  }
  void makeWorld(double dt) {
    world_ = dart::simulation::World::create();
    world_->setGravity(chain_.gravity);
    world_->setTimeStep(dt);
    world_->addSkeleton(skeleton_);
  }

  const PeerFourBar* four_bar_ = nullptr;  // the servo's four-bar, or nullptr (a chain)
  dart::dynamics::RevoluteJoint* crank_ = nullptr;
  dart::dynamics::TranslationalJoint* anchor_ = nullptr;  // the moving anchor's joint, or nullptr (fixed)
  dart::dynamics::SkeletonPtr follower_;
  dart::dynamics::SkeletonPtr skeleton_;
  dart::simulation::WorldPtr world_;
  std::vector<BodyNode*> nodes_;
};

Peer dartPeer() {
  Peer p;
  p.name = "dart/ball";
  p.version =
      std::string("DART ") + DART_VERSION +
      ": Skeleton of BallJoints, articulated-body dynamics, its semi-implicit Euler, no shapes; a shaking anchor "
      "on a VELOCITY-actuated TranslationalJoint";
  p.make = [](const PeerChain& chain, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<DartSim>(chain, dt);
  };
  p.four_bar_version =
      "DART: two skeletons (RevoluteJoint crank + BallJoint coupler, RevoluteJoint follower) closed by a "
      "BallJointConstraint, its defaults (error reduction " +
      std::to_string(dart::constraint::JointConstraint::getErrorReductionParameter()) +
      " per step); the servo as the crank joint's force";
  p.makeFourBar = [](const PeerFourBar& f, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<DartSim>(f, dt);
  };
  return p;
}

}  // namespace
}  // namespace ponyhop

extern "C" void ponyhop_peers_v3(std::vector<ponyhop::Peer>* out) { out->push_back(ponyhop::dartPeer()); }

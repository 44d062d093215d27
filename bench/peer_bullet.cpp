// The module ponyhop-peer-bullet.so, built only when CMake finds Bullet's double-precision
// libraries (libbullet-dev ships libBullet*-float64 and bullet-float64.pc beside the
// single-precision ones; bench/CMakeLists.txt, whose imported target defines BT_USE_DOUBLE_PRECISION).
//
// btMultiBody (Featherstone's articulated-body algorithm in Bullet, reduced coordinates) with a
// fixed base at the anchor and one spherical joint per link, stepped by btMultiBodyDynamicsWorld
// with exactly dt per step (stepSimulation(dt, 0)). Its integrator is semi-implicit Euler. No
// damping (Bullet's default 0.04 linear/angular multibody damping is set to 0), no sleeping,
// the joint speed cap raised out of the way, no collision shapes.
//
// A moving anchor (the shake case): btMultiBody has no prescribed-motion base (a fixed base is
// taken as unaccelerated in the articulated-body pass; setBaseVel/setBasePos on it would carry the
// chain without the inertial forces), so the base is floating, of mass and inertia kAnchorMass,
// with link 0's pivot at its centre of mass (the chain's pull exerts no torque on it: it never
// turns), and before each step a base force gives it the acceleration that takes it to the
// secant velocity to the path's point at t + dt (PeerChain::secant; Bullet integrates positions
// with the new velocity). The chain's pull (tens of newtons) moves a base of 1e12 kg by
// 1e-11 m/s^2: the motion is prescribed to round-off, and the next step's target corrects it.
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLink.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <BulletDynamics/Featherstone/btMultiBodyPoint2Point.h>
#include <btBulletDynamicsCommon.h>

#include "bench/peer.h"

namespace ponyhop {
namespace {

btVector3 bt(const Eigen::Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }
Eigen::Vector3d eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

constexpr double kAnchorMass = 1e12;  // kg (and kg m^2): the moving anchor's base

class BulletSim final : public PeerSim {
 public:
  BulletSim(const PeerChain& chain, double dt) : BulletSim(chain, dt, nullptr) {
    const int n = static_cast<int>(chain.mass.size());
    // Link frames are ponyhop's (centre of mass, axis z). Built with every joint at zero (all
    // links in the base's orientation, identity), then the joints set to the t = 0 pose.
    btMultiBody* body = addMultiBody(n, chain.anchor, Eigen::Quaterniond::Identity(), chain.moving());
    const btVector3 half(0.0, 0.0, 0.5 * chain.length);
    for (int i = 0; i < n; ++i) {
      // Pivot: the link's top end, +L/2 z from its centre; from the parent's centre it is -L/2 z
      // (the anchor is the base's origin).
      const btVector3 parent_to_pivot = i == 0 ? btVector3(0, 0, 0) : -half;
      body->setupSpherical(i, chain.mass[i], bt(chain.inertia[i]), i - 1, btQuaternion::getIdentity(), parent_to_pivot,
                           -half, true);
    }
    body->finalizeMultiDof();
    for (int i = 0; i < n; ++i) {
      setSpherical(body, i, i == 0 ? chain.q[0] : chain.q[i - 1].conjugate() * chain.q[i]);
      // A spherical joint's velocity: the link's angular velocity relative to its parent, link frame.
      const Eigen::Vector3d w = chain.relativeW0(i);
      btScalar qd[3] = {w.x(), w.y(), w.z()};
      body->setJointVelMultiDof(i, qd);
    }
    if (chain.moving()) {
      body->setBaseVel(bt(chain.anchorAt(0.0).v));
      moving_ = true;
    }
    finish();
  }
  // The four-bar (bench/peer.h): two multibodies, each fixed base in its hinge's link orientation
  // at t = 0 (so that a hinge angle of zero is the t = 0 pose), closed by a btMultiBodyPoint2Point
  // between the coupler's bottom end and the follower's top end.
  BulletSim(const PeerFourBar& f, double dt) : BulletSim(f.chain, dt, &f) {
    const PeerChain& c = f.chain;
    const btVector3 half(0.0, 0.0, 0.5 * c.length);
    btMultiBody* arm = addMultiBody(2, c.anchor, c.q[0]);
    arm->setupRevolute(0, c.mass[0], bt(c.inertia[0]), -1, btQuaternion::getIdentity(), bt(c.q[0].conjugate() * f.axis),
                       btVector3(0, 0, 0), -half, true);
    arm->setupSpherical(1, c.mass[1], bt(c.inertia[1]), 0, btQuaternion::getIdentity(), -half, -half, true);
    arm->finalizeMultiDof();
    setSpherical(arm, 1, c.q[0].conjugate() * c.q[1]);
    btMultiBody* follower = addMultiBody(1, f.ground, c.q[2]);
    follower->setupRevolute(0, c.mass[2], bt(c.inertia[2]), -1, btQuaternion::getIdentity(),
                            bt(c.q[2].conjugate() * f.axis), btVector3(0, 0, 0), half, true);
    follower->finalizeMultiDof();
    // The solver takes a multibody constraint in the simulation island of its links' colliders: each
    // link gets one (a point sphere in no collision group, so it never touches anything).
    for (btMultiBody* body : {arm, follower}) {
      for (int i = 0; i < body->getNumLinks(); ++i) {
        colliders_.push_back(std::make_unique<btMultiBodyLinkCollider>(body, i));
        colliders_.back()->setCollisionShape(&point_);
        body->getLink(i).m_collider = colliders_.back().get();
      }
    }
    closure_ = std::make_unique<btMultiBodyPoint2Point>(arm, 1, follower, 0, -half, half);
    world_.addMultiBodyConstraint(closure_.get());
    finish();
    for (auto& collider : colliders_) world_.addCollisionObject(collider.get(), 0, 0);
  }
  ~BulletSim() override {
    if (closure_) world_.removeMultiBodyConstraint(closure_.get());
    for (auto& collider : colliders_) world_.removeCollisionObject(collider.get());
    for (auto& b : bodies_) world_.removeMultiBody(b.get());
  }

  void step() override {
    if (four_bar_ && four_bar_->servo()) {
      links(scratch_);
      bodies_[0]->addJointTorque(0, four_bar_->servoTorque(scratch_[0], time_));  // cleared by the step
    }
    if (moving_) {
      btMultiBody& base = *bodies_[0];
      const Eigen::Vector3d x = eigen(base.getBasePos()), v = eigen(base.getBaseVel());
      const Eigen::Vector3d target = ((chain_.anchorAt(time_ + dt_).x - x) / dt_ - v) / dt_;
      base.addBaseForce(bt(kAnchorMass * (target - chain_.gravity)));  // the world adds M g; cleared by the step
    }
    world_.stepSimulation(dt_, 0);  // maxSubSteps 0: one step of exactly dt
    time_ += dt_;
  }
  double time() const override { return time_; }
  // The links of each multibody in turn.
  void links(std::vector<PeerLink>& out) override {
    out.clear();
    for (auto& body : bodies_) {
      const int n = body->getNumLinks();
      omega_.resize(n + 1);
      vel_.resize(n + 1);
      body->compTreeLinkVelocities(&omega_[0], &vel_[0]);  // index 0: the base; link frames
      for (int i = 0; i < n; ++i) {
        // compTreeLinkVelocities gives each link's velocities in its own frame.
        const btVector3 x = body->localPosToWorld(i, btVector3(0, 0, 0));
        const btMatrix3x3 to_world = body->localFrameToWorld(i, btMatrix3x3::getIdentity());
        btQuaternion q;
        to_world.getRotation(q);
        out.push_back({eigen(x), eigen(to_world * vel_[i + 1]), eigen(to_world * omega_[i + 1]),
                       Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z())});
      }
    }
  }

 private:
  BulletSim(const PeerChain& chain, double dt, const PeerFourBar* four_bar)
      : PeerSim(chain),
        dispatcher_(&config_),
        world_(&dispatcher_, &broadphase_, &solver_, &config_),
        dt_(dt),
        four_bar_(four_bar) {
    world_.setGravity(bt(chain.gravity));
  }
  // A multibody of n links on a fixed base at `origin` in orientation `q` (base to world), or on a
  // floating base of kAnchorMass there (`floating`: the moving anchor).
  btMultiBody* addMultiBody(int n, const Eigen::Vector3d& origin, const Eigen::Quaterniond& q, bool floating = false) {
    const double mass = floating ? kAnchorMass : 0.0;
    bodies_.push_back(std::make_unique<btMultiBody>(n, mass, btVector3(mass, mass, mass), !floating, false));
    btTransform base;
    base.setIdentity();
    base.setOrigin(bt(origin));
    base.setRotation(btQuaternion(q.x(), q.y(), q.z(), q.w()));
    bodies_.back()->setBaseWorldTransform(base);
    return bodies_.back().get();
  }
  // Bullet's spherical joint coordinate is the child-to-parent rotation Q = q_p^-1 q_i.
  static void setSpherical(btMultiBody* body, int i, const Eigen::Quaterniond& rel) {
    btScalar pos[4] = {rel.x(), rel.y(), rel.z(), rel.w()};
    body->setJointPosMultiDof(i, pos);
  }
  // No damping (Bullet's default 0.04), no sleeping, the speed cap out of the way; then into the world.
  void finish() {
    for (auto& body : bodies_) {
      body->setLinearDamping(0.0);
      body->setAngularDamping(0.0);
      body->setCanSleep(false);
      body->setMaxCoordinateVelocity(1e30);
      body->setUseGyroTerm(true);
      body->setHasSelfCollision(false);
      world_.addMultiBody(body.get());
      btAlignedObjectArray<btQuaternion> scratch_q;
      btAlignedObjectArray<btVector3> scratch_m;
      body->forwardKinematics(scratch_q, scratch_m);
    }
  }

  btDefaultCollisionConfiguration config_;
  btCollisionDispatcher dispatcher_;
  btDbvtBroadphase broadphase_;
  btMultiBodyConstraintSolver solver_;
  btMultiBodyDynamicsWorld world_;
  std::vector<std::unique_ptr<btMultiBody>> bodies_;
  btSphereShape point_{1e-4};
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders_;
  std::unique_ptr<btMultiBodyPoint2Point> closure_;
  btAlignedObjectArray<btVector3> omega_, vel_;
  double dt_;
  const PeerFourBar* four_bar_;
  bool moving_ = false;  // the base is the moving anchor
  double time_ = 0.0;
};

Peer bulletPeer() {
  Peer p;
  p.name = "bullet/multibody";
  const int v = btGetVersion();  // 324 for 3.24
  p.version =
      "Bullet " + std::to_string(v / 100) + "." + std::to_string(v % 100) +
      " btMultiBody, double precision (BT_USE_DOUBLE_PRECISION, the -float64 libraries): spherical joints, "
      "its semi-implicit Euler, damping 0, no sleeping, no collision shapes; a shaking anchor as a floating 1e12 kg "
      "base forced to the path";
  p.make = [](const PeerChain& chain, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<BulletSim>(chain, dt);
  };
  p.four_bar_version =
      "Bullet: two btMultiBody trees (revolute crank + spherical coupler, revolute follower) closed by a "
      "btMultiBodyPoint2Point, the constraint solver's default settings; the servo as a joint torque";
  p.makeFourBar = [](const PeerFourBar& f, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<BulletSim>(f, dt);
  };
  return p;
}

}  // namespace
}  // namespace ponyhop

extern "C" void ponyhop_peers_v3(std::vector<ponyhop::Peer>* out) { out->push_back(ponyhop::bulletPeer()); }

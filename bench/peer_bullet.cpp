// The module ponyhop-peer-bullet.so, built only when CMake finds Bullet's double-precision
// libraries (libbullet-dev ships libBullet*-float64 and bullet-float64.pc beside the
// single-precision ones; bench/CMakeLists.txt, whose imported target defines BT_USE_DOUBLE_PRECISION).
//
// btMultiBody (Featherstone's articulated-body algorithm in Bullet, reduced coordinates) with a
// fixed base at the anchor and one spherical joint per link, stepped by btMultiBodyDynamicsWorld
// with exactly dt per step (stepSimulation(dt, 0)). Its integrator is semi-implicit Euler. No
// damping (Bullet's default 0.04 linear/angular multibody damping is set to 0), no sleeping,
// the joint speed cap raised out of the way, no collision shapes.
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLink.h>
#include <btBulletDynamicsCommon.h>

#include "bench/peer.h"

namespace ponyhop {
namespace {

btVector3 bt(const Eigen::Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }
Eigen::Vector3d eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

class BulletSim final : public PeerSim {
 public:
  BulletSim(const PeerChain& chain, double dt)
      : PeerSim(chain), dispatcher_(&config_), world_(&dispatcher_, &broadphase_, &solver_, &config_), dt_(dt) {
    const int n = static_cast<int>(chain.mass.size());
    // Link frames are ponyhop's (centre of mass, axis z). Built with every joint at zero (all
    // links in the base's orientation, identity), then the joints set to the t = 0 pose.
    body_ = std::make_unique<btMultiBody>(n, 0.0, btVector3(0, 0, 0), true, false);
    btTransform base;
    base.setIdentity();
    base.setOrigin(bt(chain.anchor));
    body_->setBaseWorldTransform(base);
    const btVector3 half(0.0, 0.0, 0.5 * chain.length);
    for (int i = 0; i < n; ++i) {
      // Pivot: the link's top end, +L/2 z from its centre; from the parent's centre it is -L/2 z
      // (the anchor is the base's origin).
      const btVector3 parent_to_pivot = i == 0 ? btVector3(0, 0, 0) : -half;
      body_->setupSpherical(i, chain.mass[i], bt(chain.inertia[i]), i - 1, btQuaternion::getIdentity(), parent_to_pivot,
                            -half, true);
    }
    body_->finalizeMultiDof();
    for (int i = 0; i < n; ++i) {
      // Bullet's spherical joint coordinate is the child-to-parent rotation Q = q_p^-1 q_i.
      const Eigen::Quaterniond rel = i == 0 ? chain.q[0] : chain.q[i - 1].conjugate() * chain.q[i];
      btScalar pos[4] = {rel.x(), rel.y(), rel.z(), rel.w()};
      body_->setJointPosMultiDof(i, pos);
    }
    body_->setLinearDamping(0.0);
    body_->setAngularDamping(0.0);
    body_->setCanSleep(false);
    body_->setMaxCoordinateVelocity(1e30);
    body_->setUseGyroTerm(true);
    body_->setHasSelfCollision(false);
    world_.setGravity(bt(chain.gravity));
    world_.addMultiBody(body_.get());
    btAlignedObjectArray<btQuaternion> scratch_q;
    btAlignedObjectArray<btVector3> scratch_m;
    body_->forwardKinematics(scratch_q, scratch_m);
    omega_.resize(n + 1);
    vel_.resize(n + 1);
  }
  ~BulletSim() override { world_.removeMultiBody(body_.get()); }

  void step() override {
    world_.stepSimulation(dt_, 0);  // maxSubSteps 0: one step of exactly dt
    time_ += dt_;
  }
  double time() const override { return time_; }
  void links(std::vector<PeerLink>& out) override {
    const int n = body_->getNumLinks();
    body_->compTreeLinkVelocities(&omega_[0], &vel_[0]);  // index 0: the base; link frames
    out.resize(n);
    for (int i = 0; i < n; ++i) {
      // compTreeLinkVelocities gives each link's velocities in its own frame.
      const btVector3 x = body_->localPosToWorld(i, btVector3(0, 0, 0));
      const btMatrix3x3 to_world = body_->localFrameToWorld(i, btMatrix3x3::getIdentity());
      btQuaternion q;
      to_world.getRotation(q);
      out[i].x = eigen(x);
      out[i].q = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
      out[i].w = eigen(to_world * omega_[i + 1]);
      out[i].v = eigen(to_world * vel_[i + 1]);
    }
  }

 private:
  btDefaultCollisionConfiguration config_;
  btCollisionDispatcher dispatcher_;
  btDbvtBroadphase broadphase_;
  btMultiBodyConstraintSolver solver_;
  btMultiBodyDynamicsWorld world_;
  std::unique_ptr<btMultiBody> body_;
  btAlignedObjectArray<btVector3> omega_, vel_;
  double dt_;
  double time_ = 0.0;
};

Peer bulletPeer() {
  Peer p;
  p.name = "bullet/multibody";
  const int v = btGetVersion();  // 324 for 3.24
  p.version = "Bullet " + std::to_string(v / 100) + "." + std::to_string(v % 100) +
              " btMultiBody, double precision (BT_USE_DOUBLE_PRECISION, the -float64 libraries): spherical joints, "
              "its semi-implicit Euler, damping 0, no sleeping, no collision shapes";
  p.make = [](const PeerChain& chain, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<BulletSim>(chain, dt);
  };
  return p;
}

}  // namespace
}  // namespace ponyhop

extern "C" void ponyhop_peers_v1(std::vector<ponyhop::Peer>* out) { out->push_back(ponyhop::bulletPeer()); }

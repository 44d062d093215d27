// The module ponyhop-peer-ode.so, built only when CMake finds ODE (libode-dev, built with dDOUBLE;
// bench/CMakeLists.txt).
//
// ODE works in maximal coordinates with velocity-level multipliers, like ponyhop's dense and
// tree solvers: one rigid body per link, a ball joint at each pivot, semi-implicit Euler. Two
// steppers: dWorldStep (a direct LCP factorization, O(m^3)) and dWorldQuickStep (projected
// Gauss-Seidel, 20 iterations by default). ODE's defaults are kept (ERP 0.2: joint drift pulled
// back by 20 % per step; CFM 1e-10), gyroscopic mode on, no auto-disable, no collision.
//
// A moving anchor (the shake case) is a kinematic body (dBodySetKinematic: infinite mass, moved by
// its velocity) that link 0's ball joint holds: before each step it is put on the prescribed path
// at t and given the secant velocity to the path at t + dt (PeerChain::secant), which ODE's
// velocity-level joint holds link 0's top end to and with which it moves the anchor to the path's
// point at t + dt. ODE is given no acceleration: the joint's velocity constraint is its way.
#include <ode/ode.h>

#include "bench/peer.h"

namespace ponyhop {
namespace {

struct OdeInit {
  OdeInit() { dInitODE2(0); }
  ~OdeInit() { dCloseODE(); }
};

class OdeSim final : public PeerSim {
 public:
  OdeSim(const PeerChain& chain, double dt, bool quick) : PeerSim(chain), dt_(dt), quick_(quick) {
    static OdeInit init;
    world_ = dWorldCreate();
    dWorldSetGravity(world_, chain.gravity.x(), chain.gravity.y(), chain.gravity.z());
    dWorldSetAutoDisableFlag(world_, 0);
    Eigen::Vector3d pivot = chain.anchor;
    dBodyID parent = nullptr;  // 0: the static environment (the fixed anchor)
    if (chain.moving()) {
      anchor_ = dBodyCreate(world_);
      dBodySetKinematic(anchor_);
      dBodySetPosition(anchor_, pivot.x(), pivot.y(), pivot.z());
      parent = anchor_;
    }
    for (size_t i = 0; i < chain.mass.size(); ++i) {
      const Eigen::Vector3d x = pivot - chain.q[i] * Eigen::Vector3d(0.0, 0.0, 0.5 * chain.length);
      dBodyID b = addBody(i, x);
      const Eigen::Vector3d v = chain.v0(i), w = chain.w0(i);
      dBodySetLinearVel(b, v.x(), v.y(), v.z());
      dBodySetAngularVel(b, w.x(), w.y(), w.z());
      ball(parent, b, pivot);
      parent = b;
      pivot = x - chain.q[i] * Eigen::Vector3d(0.0, 0.0, 0.5 * chain.length);
    }
  }
  // The four-bar (bench/peer.h): hinges at the anchor and at the ground pivot, ball joints at the
  // coupler's ends (the closure is one more ball joint: maximal coordinates have no tree).
  OdeSim(const PeerFourBar& f, double dt, bool quick) : PeerSim(f.chain), dt_(dt), quick_(quick), four_bar_(&f) {
    static OdeInit init;
    const PeerChain& c = f.chain;
    const Eigen::Vector3d half(0.0, 0.0, 0.5 * c.length);
    world_ = dWorldCreate();
    dWorldSetGravity(world_, c.gravity.x(), c.gravity.y(), c.gravity.z());
    dWorldSetAutoDisableFlag(world_, 0);
    dBodyID crank = addBody(0, c.anchor - c.q[0] * half);
    dBodyID coupler = addBody(1, c.anchor - c.q[0] * (2.0 * half) - c.q[1] * half);
    dBodyID follower = addBody(2, f.ground + c.q[2] * half);
    hinge(crank, c.anchor, f.axis);
    ball(crank, coupler, c.anchor - c.q[0] * (2.0 * half));
    hinge(follower, f.ground, f.axis);
    ball(coupler, follower, f.ground + c.q[2] * (2.0 * half));
  }
  ~OdeSim() override { dWorldDestroy(world_); }

  void step() override {
    if (four_bar_ && four_bar_->servo()) {
      links(scratch_);
      const Eigen::Vector3d tau = four_bar_->servoTorque(scratch_[0], time_) * four_bar_->axis;
      dBodyAddTorque(bodies_[0], tau.x(), tau.y(), tau.z());  // cleared by the step
    }
    if (anchor_) {
      const Eigen::Vector3d x = chain_.anchorAt(time_).x, v = chain_.secant(time_, dt_);
      dBodySetPosition(anchor_, x.x(), x.y(), x.z());
      dBodySetLinearVel(anchor_, v.x(), v.y(), v.z());
    }
    if (quick_)
      dWorldQuickStep(world_, dt_);
    else
      dWorldStep(world_, dt_);
    time_ += dt_;
  }
  double time() const override { return time_; }
  void links(std::vector<PeerLink>& out) override {
    out.resize(bodies_.size());
    for (size_t i = 0; i < bodies_.size(); ++i) {
      const dReal* x = dBodyGetPosition(bodies_[i]);
      const dReal* q = dBodyGetQuaternion(bodies_[i]);
      const dReal* v = dBodyGetLinearVel(bodies_[i]);
      const dReal* w = dBodyGetAngularVel(bodies_[i]);
      out[i].x = {x[0], x[1], x[2]};
      out[i].q = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
      out[i].v = {v[0], v[1], v[2]};
      out[i].w = {w[0], w[1], w[2]};
    }
  }

 private:
  dBodyID addBody(size_t i, const Eigen::Vector3d& x) {
    const Eigen::Quaterniond& q = chain_.q[i];
    dBodyID b = dBodyCreate(world_);
    dMass m;
    dMassSetParameters(&m, chain_.mass[i], 0, 0, 0, chain_.inertia[i].x(), chain_.inertia[i].y(), chain_.inertia[i].z(),
                       0, 0, 0);
    dBodySetMass(b, &m);
    dBodySetPosition(b, x.x(), x.y(), x.z());
    const dQuaternion oq = {q.w(), q.x(), q.y(), q.z()};
    dBodySetQuaternion(b, oq);
    dBodySetGyroscopicMode(b, 1);
    bodies_.push_back(b);
    return b;
  }
  void ball(dBodyID a, dBodyID b, const Eigen::Vector3d& pivot) {
    dJointID j = dJointCreateBall(world_, nullptr);
    dJointAttach(j, a, b);
    dJointSetBallAnchor(j, pivot.x(), pivot.y(), pivot.z());
  }
  void hinge(dBodyID b, const Eigen::Vector3d& pivot, const Eigen::Vector3d& axis) {
    dJointID j = dJointCreateHinge(world_, nullptr);
    dJointAttach(j, b, nullptr);  // to the static environment
    dJointSetHingeAnchor(j, pivot.x(), pivot.y(), pivot.z());
    dJointSetHingeAxis(j, axis.x(), axis.y(), axis.z());
  }

  dWorldID world_;
  dBodyID anchor_ = nullptr;  // the moving anchor (kinematic), or nullptr (fixed: the environment)
  std::vector<dBodyID> bodies_;
  double dt_;
  bool quick_;
  const PeerFourBar* four_bar_ = nullptr;  // the servo's four-bar, or nullptr (a chain)
  double time_ = 0.0;
};

Peer odePeer(bool quick) {
  Peer p;
  p.name = quick ? "ode/quickstep" : "ode/worldstep";
  p.version =
      "ODE (libode-dev, double precision): maximal coordinates, ball joints, dWorldStep (direct) and "
      "dWorldQuickStep (20 Gauss-Seidel iterations), its defaults ERP 0.2, CFM 1e-10, gyroscopic term on; a shaking "
      "anchor as a kinematic body";
  p.make = [quick](const PeerChain& chain, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<OdeSim>(chain, dt, quick);
  };
  p.four_bar_version =
      "ODE: maximal coordinates, hinges at the ground pivots, ball joints at the coupler's ends (the closure one of "
      "them), ERP 0.2, CFM 1e-10; the servo as a torque on the crank";
  p.makeFourBar = [quick](const PeerFourBar& f, double dt, std::string&) -> std::unique_ptr<PeerSim> {
    return std::make_unique<OdeSim>(f, dt, quick);
  };
  return p;
}

}  // namespace
}  // namespace ponyhop

extern "C" void ponyhop_peers_v3(std::vector<ponyhop::Peer>* out) {
  out->push_back(ponyhop::odePeer(false));
  out->push_back(ponyhop::odePeer(true));
}

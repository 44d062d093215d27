// The interface between `ponyhop bench` and a peer engine's module (docs/bench/README.md):
// MuJoCo (libmujoco-dev), Bullet's btMultiBody in double precision (libbullet-dev's -float64
// libraries), ODE with dWorldStep and dWorldQuickStep (libode-dev, double precision) and DART
// (libdart-dev). Each engine is a module of its own, ponyhop-peer-<engine>.so (bench/peer_<engine>.cpp),
// built only when bench/CMakeLists.txt finds the engine's Debian package; the `ponyhop` executable
// is the same whichever were found, and loads the modules it finds at run time (bench/bench_peers.h).
// This header is all a module sees of ponyhop: Eigen and the C++ library, everything inline, so
// that a module links nothing of ponyhop's.
//
// Every peer builds the same chain (a PeerChain read from the built World: exact masses and
// principal inertias, link length, gravity, the initial orientations and velocities, the anchor
// and its prescribed motion), with ball joints, no damping, contact, limits or armature, and steps
// it at the same dt. A moving anchor (the bench's shake case) is driven as each engine allows
// (bench/peer_<engine>.cpp says how); the engines that integrate with semi-implicit Euler are given
// the anchor's secant velocity over each step (PeerChain::secant), so that their anchor is on the
// prescribed path at every step's end. The peers
// work in reduced coordinates (MuJoCo, Bullet, DART: joints hold by construction) or with
// maximal coordinates and joint error correction (ODE: its defaults, ERP 0.2, CFM 1e-10).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ponyhop {

// The anchor's prescribed state at a time (world; the anchor does not rotate).
struct PeerAnchorState {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  // m/s
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  // m/s^2
};

// The chain as the peers need it: link i's top end is link i-1's bottom end (link 0's is the
// anchor); each link's frame (ponyhop's) has its centre of mass at the origin and its axis
// along z, the top end at +length/2 z.
struct PeerChain {
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double length = 0.0;                   // m, each link
  std::vector<double> mass;              // kg
  std::vector<double> radius;            // m (drawing only: the inertia is given explicitly)
  std::vector<Eigen::Vector3d> inertia;  // kg m^2, principal, link frame
  std::vector<Eigen::Quaterniond> q;     // link to world at t = 0
  // The links' velocities at t = 0 (world; centre of mass, angular): empty, the chain starts at
  // rest. On a shaking anchor the chain at rest takes Kelvin's velocities at t = 0 (the least
  // kinetic energy that meets the moving anchor: physics/models/chain.h); the peers start from them.
  std::vector<Eigen::Vector3d> v, w;
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  // The anchor's prescribed motion; empty: fixed at `anchor`. motion(0).x is `anchor`.
  std::function<PeerAnchorState(double t)> motion;

  bool moving() const { return static_cast<bool>(motion); }
  PeerAnchorState anchorAt(double t) const {
    if (motion) return motion(t);
    PeerAnchorState s;
    s.x = anchor;
    return s;
  }
  // The velocity that takes the anchor from its prescribed place at t to its place at t + dt (m/s).
  Eigen::Vector3d secant(double t, double dt) const { return (anchorAt(t + dt).x - anchorAt(t).x) / dt; }
  // Link i's velocities at t = 0 (zero when the chain starts at rest).
  Eigen::Vector3d v0(size_t i) const { return i < v.size() ? v[i] : Eigen::Vector3d::Zero(); }
  Eigen::Vector3d w0(size_t i) const { return i < w.size() ? w[i] : Eigen::Vector3d::Zero(); }
  // Link i's angular velocity relative to its parent (link i-1, or the non-rotating anchor) at
  // t = 0, in link i's frame: a ball joint's velocity coordinates in MuJoCo, Bullet and DART.
  Eigen::Vector3d relativeW0(size_t i) const {
    return q[i].conjugate() * (w0(i) - (i == 0 ? Eigen::Vector3d::Zero() : w0(i - 1)));
  }
};

// One link's state in world coordinates (centre of mass, link to world, velocities).
struct PeerLink {
  Eigen::Vector3d x, v, w;
  Eigen::Quaterniond q;
};

// A peer engine's chain, stepped in place.
class PeerSim {
 public:
  virtual ~PeerSim() = default;
  virtual void step() = 0;
  virtual double time() const = 0;
  // The links' states after the last step (the engine's own forward kinematics).
  virtual void links(std::vector<PeerLink>& out) = 0;

  // Kinetic + potential energy (J, potential -m g . x).
  virtual double energy() {
    links(scratch_);
    double e = 0.0;
    for (size_t i = 0; i < scratch_.size(); ++i) {
      const PeerLink& l = scratch_[i];
      const Eigen::Matrix3d r = l.q.normalized().toRotationMatrix();
      const Eigen::Vector3d w_body = r.transpose() * l.w;
      e += 0.5 * chain_.mass[i] * l.v.squaredNorm() + 0.5 * w_body.dot(chain_.inertia[i].cwiseProduct(w_body)) -
           chain_.mass[i] * chain_.gravity.dot(l.x);
    }
    return e;
  }

  // The free end of the last link, m.
  Eigen::Vector3d tip() {
    links(scratch_);
    const PeerLink& l = scratch_.back();
    return l.x + l.q.normalized() * Eigen::Vector3d(0.0, 0.0, -0.5 * chain_.length);
  }

  // false when the state is non-finite or ran away (|coordinate| > 1e10).
  virtual bool finite() {
    links(scratch_);
    for (const PeerLink& l : scratch_) {
      for (const Eigen::Vector3d& v : {l.x, l.v, l.w}) {
        if (!v.allFinite() || v.cwiseAbs().maxCoeff() > 1e10) return false;
      }
      if (!l.q.coeffs().allFinite()) return false;
    }
    return true;
  }

 protected:
  explicit PeerSim(const PeerChain& chain) : chain_(chain) {}
  const PeerChain& chain_;
  std::vector<PeerLink> scratch_;
};

// The RSSR four-bar (assets/scenes/four_bar.json) as the peers build it: `chain` holds its three
// links (crank, coupler, follower; their masses, inertias and t = 0 orientations, the crank's
// pivot as the anchor). Each peer builds it as two trees closed by a point-to-point constraint:
//
//   tree 1   the crank on a hinge about `axis` at the anchor (its top end), the coupler on a ball
//            joint at the crank's bottom end
//   tree 2   the follower on a hinge about `axis` at `ground` (its bottom end)
//   closure  the coupler's bottom end and the follower's top end kept together (the engine's own
//            point-to-point constraint: the loop's joint, whose error the bench reports)
//
// PeerSim::links() gives crank, coupler, follower in that order. The servo turns the crank (our
// HingeServo's law, physics/hinge_joint.h): tau = -(k e + c (w . axis - speed)) about `axis`,
// e = the crank's angle from its t = 0 pose minus speed t in (-pi, pi]; the peers apply it as a
// joint torque computed from the state at the start of each step and held over the step.
struct PeerFourBar {
  PeerChain chain;
  Eigen::Vector3d axis{0.0, 1.0, 0.0};  // both ground hinges (world, unit)
  Eigen::Vector3d ground = Eigen::Vector3d::Zero();
  double speed = 0.0, stiffness = 0.0, damping = 0.0;  // the servo (rad/s, N m/rad, N m s/rad)

  bool servo() const { return stiffness != 0.0 || damping != 0.0; }
  // The servo's torque about `axis` on the crank at time t, from its link state (N m).
  double servoTorque(const PeerLink& crank, double t) const {
    const Eigen::AngleAxisd turned((crank.q.normalized() * chain.q[0].conjugate()).normalized());
    double angle = turned.angle() * (turned.axis().dot(axis) < 0.0 ? -1.0 : 1.0);
    double e = std::remainder(angle - speed * t, 2.0 * 3.14159265358979323846);
    if (e <= -3.14159265358979323846) e += 2.0 * 3.14159265358979323846;
    return -(stiffness * e + damping * (crank.w.dot(axis) - speed));
  }

  // The largest position gap (m) of the four joints: the crank's pivot against the anchor, the
  // coupler's top end against the crank's bottom end, the follower's bottom end against `ground`,
  // and the closure (the coupler's bottom end against the follower's top end).
  double jointError(const std::vector<PeerLink>& links) const {
    const auto end = [&](int i, double sign) {
      return Eigen::Vector3d(links[i].x +
                             links[i].q.normalized() * Eigen::Vector3d(0.0, 0.0, sign * 0.5 * chain.length));
    };
    return std::max({(end(0, 1.0) - chain.anchor).norm(), (end(1, 1.0) - end(0, -1.0)).norm(),
                     (end(2, -1.0) - ground).norm(), closure(links)});
  }
  // The closure's gap alone (m).
  double closure(const std::vector<PeerLink>& links) const {
    const Eigen::Vector3d half(0.0, 0.0, 0.5 * chain.length);
    return (links[1].x - links[1].q.normalized() * half - (links[2].x + links[2].q.normalized() * half)).norm();
  }
};

// An engine and one of its integrators: "mujoco/RK4", "bullet/multibody", "ode/quickstep".
struct Peer {
  std::string name;
  std::string version;  // the engine and its settings, for the notes
  // The chain in its t = 0 pose and velocities, its anchor fixed or moving as the PeerChain says;
  // nullptr with `error` set when the engine refused it (or cannot move its anchor so).
  std::function<std::unique_ptr<PeerSim>(const PeerChain&, double dt, std::string& error)> make;
  // The four-bar in its t = 0 pose, servo on when its gains are; nullptr with `error` set when
  // the engine refused it. The PeerSim keeps a reference to the four-bar's chain.
  std::function<std::unique_ptr<PeerSim>(const PeerFourBar&, double dt, std::string& error)> makeFourBar;
  std::string four_bar_version;  // how the engine closes the loop, for the notes
};

// The name of the one symbol a module exports (found with dlsym), declared below.
inline constexpr const char* kPeerEntry = "ponyhop_peers_v3";

}  // namespace ponyhop

// A module's entry point: appends its engine's peers to `out`. The module and the executable share
// the types above, so both must come from one build; the version in the name makes a module built
// against another layout of them fail to load (with a message) rather than crash.
extern "C" void ponyhop_peers_v3(std::vector<ponyhop::Peer>* out);

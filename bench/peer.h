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
// principal inertias, link length, gravity, the initial orientations, the fixed anchor), with
// ball joints, no damping, contact, limits or armature, and steps it at the same dt. The peers
// work in reduced coordinates (MuJoCo, Bullet, DART: joints hold by construction) or with
// maximal coordinates and joint error correction (ODE: its defaults, ERP 0.2, CFM 1e-10).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ponyhop {

// The chain as the peers need it: link i's top end is link i-1's bottom end (link 0's is the
// fixed anchor); each link's frame (ponyhop's) has its centre of mass at the origin and its axis
// along z, the top end at +length/2 z.
struct PeerChain {
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double length = 0.0;                   // m, each link
  std::vector<double> mass;              // kg
  std::vector<double> radius;            // m (drawing only: the inertia is given explicitly)
  std::vector<Eigen::Vector3d> inertia;  // kg m^2, principal, link frame
  std::vector<Eigen::Quaterniond> q;     // link to world at t = 0 (the chain starts at rest)
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
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

// An engine and one of its integrators: "mujoco/RK4", "bullet/multibody", "ode/quickstep".
struct Peer {
  std::string name;
  std::string version;  // the engine and its settings, for the notes
  // A chain at rest in its t = 0 pose; nullptr with `error` set when the engine refused it.
  std::function<std::unique_ptr<PeerSim>(const PeerChain&, double dt, std::string& error)> make;
};

// The name of the one symbol a module exports (found with dlsym), declared below.
inline constexpr const char* kPeerEntry = "ponyhop_peers_v1";

}  // namespace ponyhop

// A module's entry point: appends its engine's peers to `out`. The module and the executable share
// the types above, so both must come from one build; the version in the name makes a module built
// against another layout of them fail to load (with a message) rather than crash.
extern "C" void ponyhop_peers_v1(std::vector<ponyhop::Peer>* out);

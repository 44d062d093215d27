// Other engines run side by side with ponyhop's methods in `ponyhop bench` (docs/bench/README.md):
// MuJoCo (libmujoco-dev), Bullet's btMultiBody in double precision (libbullet-dev's -float64
// libraries), ODE with dWorldStep and dWorldQuickStep (libode-dev, double precision) and DART
// (libdart-dev). Each is optional: app/CMakeLists.txt compiles an engine's file and defines
// PONYHOP_HAVE_<ENGINE> only when its Debian package was found at configure time.
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

#include "app/bench_run.h"
#include "sim/sim.h"

namespace ponyhop {

// The chain as the peers need it: link i's top end is link i-1's bottom end (link 0's is the
// fixed anchor); each link's frame (ponyhop's) has its centre of mass at the origin and its axis
// along z, the top end at +length/2 z.
struct PeerChain {
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double length = 0.0;                    // m, each link
  std::vector<double> mass;               // kg
  std::vector<double> radius;             // m (drawing only: the inertia is given explicitly)
  std::vector<Eigen::Vector3d> inertia;   // kg m^2, principal, link frame
  std::vector<Eigen::Quaterniond> q;      // link to world at t = 0 (the chain starts at rest)
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
};

// One link's state in world coordinates (centre of mass, link to world, velocities).
struct PeerLink {
  Eigen::Vector3d x, v, w;
  Eigen::Quaterniond q;
};

// The chain of a built scene (its chain, fixed anchor) as the peers build it.
PeerChain peerChainOf(const Sim& rt);

// A peer engine's chain, stepped in place.
class PeerSim {
 public:
  virtual ~PeerSim() = default;
  virtual void step() = 0;
  virtual double time() const = 0;
  // The links' states after the last step (the engine's own forward kinematics).
  virtual void links(std::vector<PeerLink>& out) = 0;
  // Kinetic + potential energy (J, potential -m g . x).
  virtual double energy();
  // The free end of the last link, m.
  Eigen::Vector3d tip();
  // false when the state is non-finite or ran away (|coordinate| > 1e10).
  virtual bool finite();

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

// The peers compiled in (empty when none was found at configure time).
std::vector<Peer> availablePeers();
// One note per engine (its version and settings, or that it was not found).
std::vector<std::string> peerNotes();

// One peer run, measured like benchRun(): `repeats` timed runs of [0, horizon], the tip's error
// against the reference, then the first repeat continued (untimed) to long_duration for the
// energy drift (against the peer's own energy at t = 0; e_start: the chain's energy in ponyhop's
// reference, for the relative drift).
RunResult benchPeerRun(const Peer& peer, const PeerChain& chain, double dt, double horizon, int repeats,
                       double long_duration, const Trajectory& reference, double e_start);

// Cost per step of the chain hanging at rest (the scaling sweep), median of blocks of steps
// within ~budget seconds.
ScalingResult benchPeerScaling(const Peer& peer, const PeerChain& chain, double dt, double budget);

// The engines' entries (defined in app/bench_<engine>.cpp when compiled in).
std::vector<Peer> mujocoPeers();
std::vector<Peer> bulletPeers();
std::vector<Peer> odePeers();
std::vector<Peer> dartPeers();

// The MJCF text of the chain with integrator "Euler" or "RK4" and timestep dt.
std::string mujocoChainXml(const PeerChain& chain, const std::string& integrator, double dt);

}  // namespace ponyhop

// The canonical chain in MuJoCo (optional: built only when CMake finds libmujoco, which defines
// PONYHOP_HAVE_MUJOCO), run side by side with ponyhop's methods in `ponyhop bench`: the same
// links (exact masses and principal inertias read from the built World), ball joints, no
// damping, armature, contact or limits, the same gravity and step. MuJoCo works in reduced
// coordinates (its joints hold by construction), so only the integrator and the step differ.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "app/bench_run.h"

namespace ponyhop {

// The chain as MuJoCo needs it: link i's top end is link i-1's bottom end (link 0's is the fixed
// anchor); each link's body frame has its axis along z from the bottom end to the top end.
struct MujocoChain {
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double length = 0.0;  // m, each link
  std::vector<double> mass;               // kg
  std::vector<double> radius;             // m (drawing only: the inertia is given explicitly)
  std::vector<Eigen::Vector3d> inertia;   // kg m^2, principal, body frame
  std::vector<Eigen::Quaterniond> q;      // body to world at t = 0
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
};

// The MJCF text of the chain with integrator "Euler" or "RK4" and timestep dt.
std::string mujocoChainXml(const MujocoChain& chain, const std::string& integrator, double dt);

// "" when MuJoCo was not found at configure time, else its version.
std::string mujocoVersion();

// One MuJoCo run, measured like benchRun(): the fixed-anchor chain (MuJoCo has no prescribed
// base acceleration for a shaking anchor here). e_start: the chain's energy in ponyhop's reference
// (for the relative drift).
RunResult benchMujocoRun(const MujocoChain& chain, const std::string& integrator, double dt, double horizon,
                         int repeats, double long_duration, const Trajectory& reference, double e_start);

}  // namespace ponyhop

// What the integrators advance: the full state of the dynamic bodies (positions, unit
// quaternions, linear and angular velocities), with accelerations given by one function of
// (t, state) — World's force stages (external, controller, joint forces) — so a multi-stage
// method re-solves the constraints at each stage, with kinematic bodies evaluated at the stage
// time. One file per family: symplectic_euler.h, rk4.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <vector>

namespace ponyhop {

struct BodyState {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // renormalized after each step
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d w = Eigen::Vector3d::Zero();  // world frame
};

struct BodyAcceleration {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();  // world frame
};

using State = std::vector<BodyState>;
using Accelerations = std::vector<BodyAcceleration>;
// Accelerations of every state entry at time t.
using AccelerationFunction = std::function<void(double t, const State& state, Accelerations& out)>;

// q' = 1/2 (0, w) q for a world-frame angular velocity w.
inline Eigen::Quaterniond quaternionRate(const Eigen::Vector3d& w, const Eigen::Quaterniond& q) {
  Eigen::Quaterniond r = Eigen::Quaterniond(0.0, w.x(), w.y(), w.z()) * q;
  r.coeffs() *= 0.5;
  return r;
}

}  // namespace ponyhop

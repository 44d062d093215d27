// What the integrators advance: the full state of the dynamic bodies (positions, unit
// quaternions, linear and angular velocities), with accelerations given by one function of
// (t, state) — World's force stages (external, controller, joint forces) — so a multi-stage
// method re-solves the constraints at each stage, with kinematic bodies evaluated at the stage
// time. One file per family: symplectic_euler.h, rk4.h, rattle.h, implicit_euler.h.
//
// The explicit methods (symplectic Euler, RK4) see the world only through the acceleration
// function. The constrained methods (RATTLE, linearly implicit Euler) need the constraint rows
// and a solver as well: they get a ConstrainedStep (below) that World fills.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "physics/constraint.h"
#include "physics/constraint_solver.h"
#include "physics/rigid_body.h"

namespace ponyhop {

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

// What World lends a constrained integrator for one step. The integrator moves the dynamic
// bodies of `bodies` in place (kinematic bodies are set by `forces`/`kinematicAt`).
struct ConstrainedStep {
  std::vector<RigidBody>& bodies;
  const Constraints& joints;
  ConstraintSystem& system;  // scratch
  ConstraintSolver& solver;  // factor/solve of J M^-1 J^T (dense, tree, ...)
  // Kinematic bodies at time t, then external + controller forces into the accumulators at the
  // bodies' current state (no gyroscopic term, no constraint force). False: the world stopped.
  std::function<bool(double t)> forces;
  // Kinematic bodies at time t (pose, velocity, acceleration) without touching the forces.
  std::function<void(double t)> kinematicAt;
};

// What a constrained step reports. A step that `failed` changed the bodies in an unusable way;
// World restores them and retries with smaller steps (or stops with `problem`).
struct ConstrainedStepResult {
  bool failed = false;
  // Why it failed (for World::status()), in a fixed buffer: a step that fails is split and
  // retried as part of normal work, and that allocates nothing either.
  std::array<char, 192> problem{};
  int iterations = 0;      // Newton / solver iterations used
  double joint_error = 0;  // max |C| after the step (m)
  bool corrected = false;  // RATTLE: the velocity-dependent forces' corrector was applied

  void fail(const char* what) { fail("%s", what); }
  template <class... Args>
  void fail(const char* format, Args... args) {
    failed = true;
    std::snprintf(problem.data(), problem.size(), format, args...);
  }
};

}  // namespace ponyhop

// Keeping joints together: the acceleration-level constraint C'' = 0 holds C only as well as
// the integrator does, so C drifts (Hecker lecture, "Cons: accuracy, stability"). Two cures:
//
//  Baumgarte: solve C'' + 2 alpha C' + beta^2 C = 0 instead (gains in PhysicsParams; applied
//    inside the joint-force stage, see constraint_solver.h).
//  Projection (post-stabilization, John survey; Ascher 1994): after each step, Newton-project the positions
//    onto C = 0 in the mass metric, then the velocities onto J v = -J_k v_k (the kinematic
//    bodies' motion is prescribed, so they do not move):
//      dq = M^-1 J^T (J M^-1 J^T)^-1 (-C)   (repeat until |C| < tolerance),
//      dv = M^-1 J^T (J M^-1 J^T)^-1 (-(J v + J_k v_k)).
//    The velocity projection is also Kelvin's minimum-energy start: of all velocities that
//    satisfy the joints, the one closest to the given one in the kinetic-energy metric.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "physics/constraint.h"
#include "physics/constraint_solver.h"
#include "physics/status.h"

namespace ponyhop {

// The projections' work space (kept between calls by the caller: a steady step allocates
// nothing). The position projection's Newton steps use rhs, y and dv as the velocity
// projection does.
struct ProjectionWork {
  std::vector<Vector6d> vel, dv;
  Eigen::VectorXd rhs, y;
};

struct [[nodiscard]] ProjectionResult {
  int iterations = 0;
  double error = 0.0;  // max joint error after the projection (m for spherical joints)
  bool converged = false;
  Status status;  // ok or what failed (singular A, non-finite correction)
};

// Positions and orientations of the dynamic bodies onto C = 0. `system` is scratch.
// Finite `max_step` (m or rad): assembly of a pose far from C = 0 (a loop closed at t = 0): first
// damped least-squares steps (Levenberg-Marquardt, by conjugate gradients: no factorization, bounded
// at a singular pose) of at most max_step each, up to max_iterations, until within 1e-6; then at
// most 20 Newton steps to `tolerance`. Infinite (the default): Newton steps alone.
ProjectionResult projectPositions(std::vector<RigidBody>& bodies, const Constraints& constraints,
                                  ConstraintSystem& system, ConstraintSolver& solver, double tolerance = 1e-12,
                                  int max_iterations = 10, double max_step = INFINITY);
// The same with the caller's work space (the Newton steps allocate nothing once it is sized; the
// assembly's damped steps still do).
ProjectionResult projectPositions(std::vector<RigidBody>& bodies, const Constraints& constraints,
                                  ConstraintSystem& system, ConstraintSolver& solver, ProjectionWork& work,
                                  double tolerance = 1e-12, int max_iterations = 10, double max_step = INFINITY);

// Symplectic Euler's projection (the constrained symplectic Euler, SHAKE's position solve; Hairer,
// Lubich & Wanner, "Geometric Numerical Integration", VII.1): post-stabilization after symplectic
// Euler corrects the positions along the END point's joint directions and leaves the velocities to
// a separate projection. Its velocity kick h a_n carries the centripetal part -h |v|^2 / r along
// the joint, which the drift then turns into a tangent velocity the end point's projection cannot
// see: every step adds about m h^2 |v|^4 / (2 r^2) of kinetic energy (docs/SOLVERS.md), a drift
// at a rate proportional to h that no dt cures (the 8-link chain's energy grows without bound and
// the projection fails after 2.3 s at every dt from 1/60 to 1/1920 s). Here the correction is an
// impulse along the START's joint directions J(q_n) that enters the velocity too:
//   v = v' + M_n^-1 J_n^T z / h,  x = x_n + h v,  w = w' + I_n^-1 (J_n^T z)_rot / h,  q = exp(h w) q_n
// with z (m kg) chosen so that C(x, q) = 0 (chord iteration on A = J M^-1 J^T, first the
// factorization the joint-force stage left at q_n, refactored at the latest iterate when an
// iteration contracts by less than 4x), then the velocities onto J v = -J_k v_k at the new
// positions (projectVelocities). The step is then symplectic Euler for the constrained system:
// the energy error stays bounded instead of drifting.
struct ShakeStart {
  Eigen::Vector3d x, v, w;  // the step's start position; the velocities symplectic Euler gave
  Eigen::Quaterniond q;     // the step's start orientation
};
struct ShakeWork {
  ConstraintSystem jn;            // J(q_n), evaluated by the joint-force stage
  std::vector<ShakeStart> start;  // per body (dynamic ones only are read)
  std::vector<Vector6d> fc;       // J_n^T z per body
  Eigen::VectorXd z, rhs, dz;
  unsigned long held_generation = 0;  // the solver's generation after the joint-force stage (A at q_n)
  double h = 0.0;                     // the step (s)
};
ProjectionResult shakePositions(std::vector<RigidBody>& bodies, const Constraints& constraints,
                                ConstraintSystem& system, ConstraintSolver& solver, ShakeWork& work, double h,
                                double tolerance = 1e-12, int max_iterations = 40);

// Velocities of the dynamic bodies onto J v = -J_k v_k (kinematic bodies' velocities as they
// are). Returns ok or what failed. `impulses` (optional): the multiplier y of every row (N s),
// dv = M^-1 J^T y; a contact reads its own rows' impulse from it.
Status projectVelocities(std::vector<RigidBody>& bodies, const Constraints& constraints, ConstraintSystem& system,
                         ConstraintSolver& solver, Eigen::VectorXd* impulses = nullptr);
// The same with the caller's work space.
Status projectVelocities(std::vector<RigidBody>& bodies, const Constraints& constraints, ConstraintSystem& system,
                         ConstraintSolver& solver, ProjectionWork& work, Eigen::VectorXd* impulses = nullptr);
// The mass-metric correction of per-body velocities `vel` with the solver already factored at
// `system`: (J M^-1 J^T) y = -J vel into work.y, M^-1 J^T y into work.dv (the kinematic bodies'
// zero). projectVelocities applies it to the bodies; RATTLE's corrector to a velocity change.
void massMetricCorrection(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                          const ConstraintSolver& solver, const std::vector<Vector6d>& vel, ProjectionWork& work);

}  // namespace ponyhop

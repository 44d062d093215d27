#include "physics/stabilization.h"

#include <algorithm>
#include <cmath>

namespace ponyhop {

namespace {

// Moves each dynamic body by its 6-vector dq (linear: the centre; angular: a small world-frame
// rotation vector, as J's angular columns are derivatives with respect to such a rotation).
// False when a correction is not finite.
bool moveBodies(std::vector<RigidBody>& bodies, const std::vector<Vector6d>& dq) {
  for (size_t i = 0; i < bodies.size(); ++i) {
    RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    if (!dq[i].allFinite()) return false;
    b.x += dq[i].head<3>();
    b.q = (quaternionFromRotationVector(dq[i].tail<3>()) * b.q).normalized();
  }
  return true;
}

// One damped least-squares step toward C = 0 (Levenberg-Marquardt): (A + mu I) y = b with
// A = J M^-1 J^T applied matrix-free (J (M^-1 J^T y)) by conjugate gradients, mu a thousandth of
// A's Rayleigh quotient along b, dq = M^-1 J^T y. Unlike the Newton step it needs no factorization
// and stays bounded at a singular pose (a straight chain whose tip must move along the chain).
std::vector<Vector6d> dampedStep(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                                 const ConstraintSolver& solver, const Eigen::VectorXd& b) {
  const auto apply = [&](const Eigen::VectorXd& y) {
    return system.times(solver.massWeightedTranspose(bodies, system, y));
  };
  const double mu = 1e-3 * b.dot(apply(b)) / b.squaredNorm();
  Eigen::VectorXd y = Eigen::VectorXd::Zero(b.size()), r = b, p = b;
  double rr = r.squaredNorm();
  for (int k = 0; k < 4 * b.size() && rr > 1e-24 * b.squaredNorm(); ++k) {
    const Eigen::VectorXd ap = apply(p) + mu * p;
    const double alpha = rr / p.dot(ap);
    y += alpha * p;
    r -= alpha * ap;
    const double rr_next = r.squaredNorm();
    p = r + (rr_next / rr) * p;
    rr = rr_next;
  }
  return solver.massWeightedTranspose(bodies, system, y);
}

}  // namespace

ProjectionResult projectPositions(std::vector<RigidBody>& bodies, const Constraints& constraints,
                                  ConstraintSystem& system, ConstraintSolver& solver, double tolerance,
                                  int max_iterations, double max_step) {
  ProjectionWork work;
  return projectPositions(bodies, constraints, system, solver, work, tolerance, max_iterations, max_step);
}

ProjectionResult projectPositions(std::vector<RigidBody>& bodies, const Constraints& constraints,
                                  ConstraintSystem& system, ConstraintSolver& solver, ProjectionWork& work,
                                  double tolerance, int max_iterations, double max_step) {
  ProjectionResult result;
  system.evaluate(bodies, constraints);
  result.error = system.maxError();
  // Assembly (finite max_step): damped least-squares steps of at most max_step until within
  // 1e-6 of C = 0 (or max_iterations), then the Newton steps below to round-off.
  while (std::isfinite(max_step) && result.error > 1e-6 && result.iterations < max_iterations) {
    const double scale = std::min(1.0, max_step / result.error);
    if (!moveBodies(bodies, dampedStep(bodies, system, solver, -scale * system.C()))) {
      result.status = Status::error("non-finite position correction");
      return result;
    }
    ++result.iterations;
    system.evaluate(bodies, constraints);
    result.error = system.maxError();
  }
  const int newton_limit = result.iterations + (std::isfinite(max_step) ? 20 : max_iterations);
  while (result.error > tolerance && result.iterations < newton_limit) {
    // Newton step on C(q) = 0 with the minimum-mass-norm correction:
    // J dq = -C, dq = M^-1 J^T y  =>  (J M^-1 J^T) y = -C.
    if (!solver.factor(bodies, system)) {
      result.status = Status::error("the constraint matrix J M^-1 J^T is singular");
      return result;
    }
    work.rhs = -system.C();
    solver.solveInto(work.rhs, work.y);
    solver.massWeightedTransposeInto(bodies, system, work.y, work.dv);
    if (!moveBodies(bodies, work.dv)) {
      result.status = Status::error("non-finite position correction");
      return result;
    }
    ++result.iterations;
    const double previous = result.error;
    system.evaluate(bodies, constraints);
    result.error = system.maxError();
    if (!(result.error < previous)) break;  // round-off floor reached (or diverging)
  }
  result.converged = result.error <= tolerance;
  return result;
}

Status projectVelocities(std::vector<RigidBody>& bodies, const Constraints& constraints, ConstraintSystem& system,
                         ConstraintSolver& solver, Eigen::VectorXd* impulses) {
  ProjectionWork work;
  return projectVelocities(bodies, constraints, system, solver, work, impulses);
}

Status projectVelocities(std::vector<RigidBody>& bodies, const Constraints& constraints, ConstraintSystem& system,
                         ConstraintSolver& solver, ProjectionWork& work, Eigen::VectorXd* impulses) {
  system.evaluate(bodies, constraints);
  if (impulses) impulses->resize(0);
  if (system.rows() == 0) return {};
  work.vel.resize(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) work.vel[i] << bodies[i].v, bodies[i].w;
  // (J M^-1 J^T) y = -(J_d v_d + J_k v_k), dv = M^-1 J^T y.
  if (!solver.factor(bodies, system)) return Status::error("the constraint matrix J M^-1 J^T is singular");
  massMetricCorrection(bodies, system, solver, work.vel, work);
  for (size_t i = 0; i < bodies.size(); ++i) {
    RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    if (!work.dv[i].allFinite()) return Status::error("non-finite velocity correction");
    b.v += work.dv[i].head<3>();
    b.w += work.dv[i].tail<3>();
  }
  if (impulses) *impulses = work.y;
  return {};
}

void massMetricCorrection(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                          const ConstraintSolver& solver, const std::vector<Vector6d>& vel, ProjectionWork& work) {
  system.timesInto(vel, work.rhs);
  work.rhs = -work.rhs;
  solver.solveInto(work.rhs, work.y);
  solver.massWeightedTransposeInto(bodies, system, work.y, work.dv);
}

}  // namespace ponyhop

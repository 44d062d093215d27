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

ProjectionResult shakePositions(std::vector<RigidBody>& bodies, const Constraints& constraints,
                                ConstraintSystem& system, ConstraintSolver& solver, ShakeWork& work, double h,
                                double tolerance, int max_iterations) {
  ProjectionResult result;
  const size_t n = bodies.size();
  const ConstraintSystem& jn = work.jn;
  const int rows = jn.rows();
  work.z.setZero(rows);
  work.fc.resize(n);
  // The positions for multiplier z: the start's velocities plus the impulse J_n^T z / h, drifted
  // over h from the start (M^-1 at the start orientation, as symplectic Euler's kick used it).
  const auto drift = [&] {
    std::fill(work.fc.begin(), work.fc.end(), Vector6d::Zero());
    if (rows > 0) jn.addTransposeTimes(work.z, bodies, work.fc);
    for (size_t i = 0; i < n; ++i) {
      RigidBody& b = bodies[i];
      if (!b.isDynamic()) continue;
      const ShakeStart& s = work.start[i];
      const Eigen::Matrix3d r = s.q.toRotationMatrix();
      b.v = s.v + work.fc[i].head<3>() / (b.mass * h);
      b.w = s.w + r * (r.transpose() * work.fc[i].tail<3>()).cwiseQuotient(b.inertia) / h;
      b.x = s.x + h * b.v;
      b.q = renormalized(quaternionFromRotationVector(h * b.w) * s.q);
    }
  };
  system.evaluate(bodies, constraints);  // the end point symplectic Euler reached (z = 0)
  bool factored = rows > 0 && solver.generation() == work.held_generation;  // A(q_n), from the joint-force stage
  double previous = 0.0;
  for (int k = 0;; ++k) {
    result.error = system.maxError();
    result.iterations = k;
    if (!std::isfinite(result.error)) {
      result.status = Status::error("non-finite position correction");
      return result;
    }
    if (result.error <= tolerance) break;
    if (k > 0 && result.error > 0.5 * previous && result.error < 1e-11) break;   // round-off floor
    if (k >= max_iterations || (k > 3 && result.error > 0.9 * previous)) break;  // not converging
    if (!factored || (k > 0 && result.error > 0.25 * previous)) {
      if (!solver.factor(bodies, system)) {
        result.status = Status::error("the constraint matrix J M^-1 J^T is singular");
        return result;
      }
      factored = true;
    }
    work.rhs = -system.C();
    solver.solveInto(work.rhs, work.dz);
    work.z += work.dz;
    previous = result.error;
    drift();
    system.evaluate(bodies, constraints);
  }
  result.converged = result.error <= 1e-11 || result.error <= tolerance;
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

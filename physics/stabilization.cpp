#include "physics/stabilization.h"

#include <cmath>

namespace ponyhop {

ProjectionResult projectPositions(std::vector<RigidBody>& bodies, const Constraints& constraints,
                                  ConstraintSystem& system, ConstraintSolver& solver, double tolerance,
                                  int max_iterations) {
  ProjectionResult result;
  system.evaluate(bodies, constraints);
  result.error = system.maxError();
  while (result.error > tolerance && result.iterations < max_iterations) {
    // Newton step on C(q) = 0 with the minimum-mass-norm correction:
    // J dq = -C, dq = M^-1 J^T y  =>  (J M^-1 J^T) y = -C.
    if (!solver.factor(bodies, system)) {
      result.status = Status::error("the constraint matrix J M^-1 J^T is singular");
      return result;
    }
    const Eigen::VectorXd y = solver.solve(-system.C());
    const std::vector<Vector6d> dq = solver.massWeightedTranspose(bodies, system, y);
    for (size_t i = 0; i < bodies.size(); ++i) {
      RigidBody& b = bodies[i];
      if (!b.isDynamic()) continue;
      if (!dq[i].allFinite()) {
        result.status = Status::error("non-finite position correction");
        return result;
      }
      // Linear part moves the centre; the angular part is a small world-frame rotation
      // vector (J's angular columns are derivatives with respect to such a rotation).
      b.x += dq[i].head<3>();
      b.q = (quaternionFromRotationVector(dq[i].tail<3>()) * b.q).normalized();
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
  VelocityProjectionWork work;
  return projectVelocities(bodies, constraints, system, solver, work, impulses);
}

Status projectVelocities(std::vector<RigidBody>& bodies, const Constraints& constraints, ConstraintSystem& system,
                         ConstraintSolver& solver, VelocityProjectionWork& work, Eigen::VectorXd* impulses) {
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
                          const ConstraintSolver& solver, const std::vector<Vector6d>& vel,
                          VelocityProjectionWork& work) {
  system.timesInto(vel, work.rhs);
  work.rhs = -work.rhs;
  solver.solveInto(work.rhs, work.y);
  solver.massWeightedTransposeInto(bodies, system, work.y, work.dv);
}

}  // namespace ponyhop

#include "physics/constraint_solver.h"

#include <limits>

namespace ponyhop {

Status ConstraintSolver::solveJointForces(std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                                          const BaumgarteGains& gains) {
  // Known accelerations: unconstrained M^-1 F_ext (with w x I w) for dynamic bodies, the
  // prescribed ones for kinematic bodies; and every body's velocity, for C' = J q'.
  // Each dynamic body's rotation and R I^-1 R^T once, shared by the free acceleration, the
  // factorization and M^-1 J^T lambda below.
  std::vector<Vector6d>& acc = acc_;
  acc.resize(bodies.size());
  inverse_inertia_.resize(bodies.size());
  if (principal_of_.size() != bodies.size()) {  // sized once: NaN matches no inertia
    principal_of_.assign(bodies.size(), Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
    principal_inverse_.resize(bodies.size());
  }
  for (size_t i = 0; i < bodies.size(); ++i) {
    const RigidBody& b = bodies[i];
    if (b.isDynamic()) {
      if (!(b.inertia == principal_of_[i])) {
        principal_of_[i] = b.inertia;
        principal_inverse_[i] = b.inertia.cwiseInverse();
      }
      const Eigen::Matrix3d r = b.rotation();
      rotateDiagonalInto(r, principal_inverse_[i], inverse_inertia_[i]);
      b.freeAcceleration(r, inverse_inertia_[i], acc[i]);
    } else {
      acc[i] << b.a, b.alpha;
    }
  }
  lambda_.setZero(system.rows());
  if (system.rows() > 0) {
    // b = -J'q' - J_d M^-1 F_ext - J_k acc_k - (2 alpha C' + beta^2 C); C' = J q' (with alpha
    // only) in the same pass over the rows as J acc.
    if (gains.alpha != 0.0) {
      system.timesInto(acc, bodies, jx_, jv_);
    } else {
      system.timesInto(acc, jx_);
    }
    if (gains.velocity_level && gains.alpha != 0.0 && gains.beta != 0.0) {
      // One pass, the same operations as the passes below: ((-J acc) - 2 alpha J q') - beta^2 C.
      rhs_ = (-jx_ - (2.0 * gains.alpha) * jv_) - (gains.beta * gains.beta) * system.C();
    } else {
      rhs_ = -jx_;
      if (!gains.velocity_level) rhs_ -= system.bias();
      if (gains.alpha != 0.0) rhs_ -= 2.0 * gains.alpha * jv_;
      if (gains.beta != 0.0) rhs_ -= gains.beta * gains.beta * system.C();
    }
    if (!factorWith(bodies, system, inverse_inertia_)) {
      return Status::error("the constraint matrix J M^-1 J^T is singular");
    }
    solveInto(rhs_, lambda_);
    if (!lambda_.allFinite()) return Status::error("non-finite multipliers lambda");
  }

  // F_c = J^T lambda; acceleration = M^-1 (F_ext + F_c) (the free part already has M^-1 F_ext).
  std::vector<Vector6d>& fc = fc_;
  fc.assign(bodies.size(), Vector6d::Zero());
  if (system.rows() > 0) system.addTransposeTimes(lambda_, bodies, fc);
  // z: 0 when every a, alpha and constraint force written is finite, else NaN (x - x is NaN for
  // an inf or NaN x, +0 otherwise), checked while the values are at hand.
  double z = 0.0;
  for (size_t i = 0; i < bodies.size(); ++i) {
    RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    b.constraint_force = fc[i].head<3>();
    b.constraint_torque = fc[i].tail<3>();
    b.a = acc[i].head<3>() + fc[i].head<3>() / b.mass;
    b.alpha = acc[i].tail<3>() + inverse_inertia_[i] * fc[i].tail<3>();
    for (int k = 0; k < 3; ++k)
      z += (b.a(k) - b.a(k)) + (b.alpha(k) - b.alpha(k)) + (b.constraint_force(k) - b.constraint_force(k));
  }
  accelerations_finite_ = z == 0.0;
  return {};
}

std::vector<Vector6d> ConstraintSolver::massWeightedTranspose(const std::vector<RigidBody>& bodies,
                                                              const ConstraintSystem& system,
                                                              const Eigen::VectorXd& y) const {
  std::vector<Vector6d> out;
  massWeightedTransposeInto(bodies, system, y, out);
  return out;
}

void ConstraintSolver::massWeightedTransposeInto(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                                                 const Eigen::VectorXd& y, std::vector<Vector6d>& out) const {
  out.assign(bodies.size(), Vector6d::Zero());
  system.addTransposeTimes(y, bodies, out);
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].isDynamic()) out[i] = applyInverseMass(bodies[i], out[i]);
  }
}

}  // namespace ponyhop

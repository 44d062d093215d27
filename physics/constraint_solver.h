// What every multiplier solver does (the "joint forces" stage), whatever its factorization:
//
//   A lambda = b,   A = J M^-1 J^T (over the dynamic bodies),
//   b = -J'q' - J_d M^-1 F_ext - J_k acc_k - (2 alpha C' + beta^2 C)
//
// (Hecker lecture, "Math to the Rescue"; J_d M^-1 F_ext includes the gyroscopic term, J_k
// acc_k are the kinematic bodies' known accelerations, the last bracket is Baumgarte's
// stabilization C'' + 2 alpha C' + beta^2 C = 0). Then F_c = J^T lambda on the dynamic bodies.
//
// A subclass supplies only the factorization of A and the solve: DenseSolver (Eigen LDLT) and
// TreeSolver (Baraff's block LDL^T in leaves-first order, O(n)), which give the same lambda.
// Position/velocity projection (stabilization.h) reuses them with the mass metric. The
// reduced-coordinate method (featherstone.h) replaces World's joint-force stage as a whole, as
// it yields accelerations without multipliers.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "physics/constraint.h"
#include "physics/rigid_body.h"
#include "physics/status.h"

namespace ponyhop {

struct BaumgarteGains {
  double alpha = 0.0;  // 1/s, C' gain (2 alpha)
  double beta = 0.0;   // 1/s, C gain (beta^2)
  // Velocity level (stabilization = velocity, alpha = 1 / (2h), beta^2 = erp / h^2): the term
  // J' v is left out, so that a symplectic Euler step of h lands on J v' = -erp C / h.
  bool velocity_level = false;
};

class ConstraintSolver {
 public:
  virtual ~ConstraintSolver() = default;

  // Factor A = J M^-1 J^T for the evaluated system and the bodies' current mass matrices.
  // Returns false when A is singular (redundant rows, a joint with no dynamic body).
  virtual bool factor(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) = 0;
  // The same with each dynamic body's world inverse inertia R I^-1 R^T already computed (by
  // solveJointForces, which needs it for the free accelerations too): a solver that uses it does
  // not build it again. The default ignores it.
  virtual bool factorWith(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                          const std::vector<Eigen::Matrix3d>& world_inverse_inertia) {
    (void)world_inverse_inertia;
    return factor(bodies, system);
  }
  // Counts factorizations (every factor() and factorWith() call, 1 after the first): a caller
  // that remembers it can tell whether the factorization it left is still the current one.
  unsigned long generation() const { return generation_; }
  // y with A y = rhs, after factor().
  virtual Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const = 0;
  // The same into `out` (resized when needed): a solver that keeps its work space allocates
  // nothing here (the tree solver); the default calls solve().
  virtual void solveInto(const Eigen::VectorXd& rhs, Eigen::VectorXd& out) const { out = solve(rhs); }

  // The joint-force stage. Needs the bodies' accumulated forces (dynamic) and prescribed
  // accelerations (kinematic). Writes constraint_force/torque and the total accelerations a,
  // alpha of every dynamic body. Returns ok or what went wrong.
  Status solveJointForces(std::vector<RigidBody>& bodies, const ConstraintSystem& system, const BaumgarteGains& gains);
  // The multipliers of the last solveJointForces (one per constraint row; a spherical joint's
  // three are its constraint force on body a, in newtons).
  const Eigen::VectorXd& lambda() const { return lambda_; }
  // Whether the last solveJointForces that succeeded wrote only finite a, alpha and constraint
  // forces (World then skips its per-body check, which would find nothing).
  bool accelerationsFinite() const { return accelerations_finite_; }

  // dq = M^-1 J^T y for the dynamic bodies (zero for the others): the mass-metric correction
  // for a multiplier-like vector y.
  std::vector<Vector6d> massWeightedTranspose(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                                              const Eigen::VectorXd& y) const;
  // The same into `out` (resized to the bodies; no allocation once it has their size).
  void massWeightedTransposeInto(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                                 const Eigen::VectorXd& y, std::vector<Vector6d>& out) const;

 protected:
  unsigned long generation_ = 0;  // factorizations so far (subclasses count theirs)

 private:
  Eigen::VectorXd lambda_;
  bool accelerations_finite_ = false;
  // Work space of solveJointForces (kept between calls: a steady step allocates nothing).
  std::vector<Vector6d> acc_, fc_;
  std::vector<Eigen::Matrix3d> inverse_inertia_;  // R I^-1 R^T per dynamic body, this step
  // I^-1 (principal, body frame) per body, and the inertia it was made from: three divisions a
  // body and step only when the inertia changed (a body's mass properties may be edited).
  std::vector<Eigen::Vector3d> principal_inverse_, principal_of_;
  Eigen::VectorXd rhs_, jx_, jv_;
};

// M^-1 x for one body's 6-vector (1/m on the linear part, I_world^-1 on the angular part), with
// its world inverse inertia R I^-1 R^T already made (a caller that needs it for many vectors).
inline Vector6d applyInverseMass(const RigidBody& b, const Eigen::Matrix3d& inverse_inertia, const Vector6d& x) {
  Vector6d out;
  out.head<3>() = x.head<3>() / b.mass;
  out.tail<3>() = inverse_inertia * x.tail<3>();
  return out;
}
inline Vector6d applyInverseMass(const RigidBody& b, const Vector6d& x) {
  return applyInverseMass(b, b.worldInverseInertia(), x);
}

}  // namespace ponyhop

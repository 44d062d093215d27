// The dense multiplier solver: A = J M^-1 J^T assembled as a dense m x m matrix from the
// per-joint Jacobian blocks, factored with Eigen's LDLT. O(m^3) per solve (Hecker's "Cons:
// O(n^3)"); the reference that sparser solvers are checked against.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

#include "physics/constraint_solver.h"

namespace ponyhop {

class DenseSolver final : public ConstraintSolver {
 public:
  bool factor(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) override;
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const override;

  const Eigen::MatrixXd& matrix() const { return a_; }  // A as last assembled (tests)

 private:
  Eigen::MatrixXd a_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  std::vector<std::vector<std::pair<int, bool>>> touching_;  // per body: (block, is side a)
};

}  // namespace ponyhop

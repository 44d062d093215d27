#include "physics/sparse_lu.h"

#include <Eigen/SparseLU>

namespace ponyhop {

namespace {

template <typename Rhs>
SparseLuResult solveWith(const Eigen::SparseMatrix<double>& a, const Rhs& b, Rhs& x) {
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  lu.compute(a);
  if (lu.info() != Eigen::Success) return SparseLuResult::Singular;
  x = lu.solve(b);
  return lu.info() == Eigen::Success ? SparseLuResult::Solved : SparseLuResult::SolveFailed;
}

}  // namespace

SparseLuResult sparseLuSolve(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  return solveWith(a, b, x);
}

SparseLuResult sparseLuSolve(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  return solveWith(a, b, x);
}

}  // namespace ponyhop

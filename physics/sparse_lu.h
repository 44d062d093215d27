// A x = b with Eigen's SparseLU (COLAMD ordering), for the few places that solve a sparse system
// (the implicit Euler KKT system, the keyframe spline). It is compiled once, in sparse_lu.cpp:
// SparseLU's instantiation costs about 7 s of compiler time in every file that makes it.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace ponyhop {

enum class SparseLuResult {
  Solved,
  Singular,     // the factorization failed (x is untouched)
  SolveFailed,  // the triangular solves failed
};

SparseLuResult sparseLuSolve(const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b, Eigen::MatrixXd& x);
SparseLuResult sparseLuSolve(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b, Eigen::VectorXd& x);

}  // namespace ponyhop

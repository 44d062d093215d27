// Small fixed-size helpers for the O(n) solvers' inner loops (tree_solver.cpp, featherstone.cpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

namespace ponyhop {

// The inverse of a symmetric positive definite 3 x 3 matrix by cofactors (Eigen's closed form):
// a fraction of Eigen::LLT's solve against the identity, which goes through its general
// triangular solver. False, like a failed Cholesky pivot, when a leading minor is not positive
// (singular or indefinite: redundant constraint rows) or the inverse is not finite.
inline bool inverseSpd3(const Eigen::Matrix3d& m, Eigen::Matrix3d& inv) {
  const double minor2 = m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0);
  if (!(m(0, 0) > 0.0 && minor2 > 0.0 && m.determinant() > 0.0)) return false;
  inv = m.inverse();
  return inv.allFinite();
}

}  // namespace ponyhop

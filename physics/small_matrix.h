// Small fixed-size helpers for the O(n) solvers' inner loops (tree_solver.cpp, featherstone.cpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>

namespace ponyhop {

// The inverse of a symmetric positive definite 3 x 3 matrix by its cofactors, read from the
// upper triangle (m is symmetric up to round-off): six cofactors, one determinant from them and
// one division, a fraction of Eigen::LLT's solve against the identity. The inverse is symmetric
// by construction. False, like a failed Cholesky pivot, when a leading minor is not positive
// (singular or indefinite: redundant constraint rows) or the inverse is not finite.
// From the upper triangle's six entries.
inline bool inverseSpd3(double m00, double m01, double m02, double m11, double m12, double m22, Eigen::Matrix3d& inv) {
  const double c00 = m11 * m22 - m12 * m12;
  const double c01 = m12 * m02 - m01 * m22;
  const double c02 = m01 * m12 - m11 * m02;
  const double det = m00 * c00 + m01 * c01 + m02 * c02;
  const double minor2 = m00 * m11 - m01 * m01;
  if (!(m00 > 0.0 && minor2 > 0.0 && det > 0.0)) return false;
  const double s = 1.0 / det;
  const double i01 = s * c01, i02 = s * c02, i12 = s * (m02 * m01 - m00 * m12);
  inv(0, 0) = s * c00;
  inv(1, 1) = s * (m00 * m22 - m02 * m02);
  inv(2, 2) = s * minor2;
  inv(0, 1) = inv(1, 0) = i01;
  inv(0, 2) = inv(2, 0) = i02;
  inv(1, 2) = inv(2, 1) = i12;
  return inv.allFinite();
}
inline bool inverseSpd3(const Eigen::Matrix3d& m, Eigen::Matrix3d& inv) {
  return inverseSpd3(m(0, 0), m(0, 1), m(0, 2), m(1, 1), m(1, 2), m(2, 2), inv);
}

// q v q^-1 for a unit quaternion q, the same operations as Eigen's q * v (uv = 2 vec x v,
// v + w uv + vec x uv) in scalars: Eigen builds its cross products through the stack and reads
// them back in 16-byte halves of 8-byte stores (failed store forwarding, a stall per rotation).
inline Eigen::Vector3d rotate(const Eigen::Quaterniond& q, const Eigen::Vector3d& v) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  const double v0 = v(0), v1 = v(1), v2 = v(2);
  double u0 = y * v2 - z * v1, u1 = z * v0 - x * v2, u2 = x * v1 - y * v0;
  u0 += u0;
  u1 += u1;
  u2 += u2;
  return Eigen::Vector3d(v0 + w * u0 + (y * u2 - z * u1), v1 + w * u1 + (z * u0 - x * u2),
                         v2 + w * u2 + (x * u1 - y * u0));
}

}  // namespace ponyhop

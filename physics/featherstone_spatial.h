// Private to physics/featherstone*.cpp: the spatial algebra helpers both halves of the
// articulated solver use (shift matrices, spatial inertias, the per-dof dispatch).
#pragma once

#include <Eigen/Core>
#include <utility>

#include "physics/featherstone.h"
#include "physics/rigid_body.h"
#include "physics/small_matrix.h"

namespace ponyhop {

namespace {

using Matrix6 = ArticulatedSystem::Matrix6;
using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 6, 1>;

// X = [ I  -d~ ; 0  I ]: velocity of the point x_i from the twist at x_p (d = x_i - x_p);
// X^T moves a force from x_i to x_p (same force, torque + d x f).
[[maybe_unused]] Matrix6 shift(const Eigen::Vector3d& d) {
  Matrix6 x = Matrix6::Identity();
  x.topRightCorner<3, 3>() = -skew(d);
  return x;
}
// X^T M X for a symmetric M = [A B; B^T E] (an articulated inertia carried from x_i to x_p) in
// 3 x 3 blocks: X = [I -K; 0 I], K = skew(d), K^T = -K, so
//   X^T M X = [ A, B - A K ; B^T + K A, E + K B - B^T K - K A K ].
// The bottom-left block is the top-right's transpose (A symmetric): symmetry is kept exactly,
// at a fraction of the two 6 x 6 products.
[[maybe_unused]] Matrix6 shiftInertia(const Eigen::Vector3d& d, const Matrix6& m) {
  const Eigen::Matrix3d k = skew(d);
  const Eigen::Matrix3d a = m.topLeftCorner<3, 3>();
  const Eigen::Matrix3d b = m.topRightCorner<3, 3>();
  const Eigen::Matrix3d ak = a * k;
  const Eigen::Matrix3d top_right = b - ak;
  const Eigen::Matrix3d kb = k * b;
  Matrix6 out;
  out.topLeftCorner<3, 3>() = a;
  out.topRightCorner<3, 3>() = top_right;
  out.bottomLeftCorner<3, 3>() = top_right.transpose();
  out.bottomRightCorner<3, 3>() = m.bottomRightCorner<3, 3>() + kb + kb.transpose() - k * ak;
  return out;
}
// M skew(r) for an N x 3 M: row i is (row i of M) x r (no products with K's zeros).
template <int N, class Derived>
Eigen::Matrix<double, N, 3> timesSkew(const Eigen::MatrixBase<Derived>& m, const Eigen::Vector3d& r) {
  Eigen::Matrix<double, N, 3> out;
  for (int i = 0; i < N; ++i) {
    const double m0 = m(i, 0), m1 = m(i, 1), m2 = m(i, 2);
    out(i, 0) = m1 * r(2) - m2 * r(1);
    out(i, 1) = m2 * r(0) - m0 * r(2);
    out(i, 2) = m0 * r(1) - m1 * r(0);
  }
  return out;
}
// skew(r) M for a 3 x 3 M: column j is r x (column j of M).
template <class Derived>
[[gnu::always_inline]] inline Eigen::Matrix3d skewTimes(const Eigen::Vector3d& r, const Eigen::MatrixBase<Derived>& m) {
  Eigen::Matrix3d out;
  const double r0 = r(0), r1 = r(1), r2 = r(2);
  for (int j = 0; j < 3; ++j) {  // in scalars: no Vector3d of the column through the stack
    const double m0 = m(0, j), m1 = m(1, j), m2 = m(2, j);
    out(0, j) = r1 * m2 - r2 * m1;
    out(1, j) = r2 * m0 - r0 * m2;
    out(2, j) = r0 * m1 - r1 * m0;
  }
  return out;
}

// The cross products in scalars (the same operations): Eigen's cross() goes through a stack
// temporary read back in 16-byte halves of 8-byte stores (failed store forwarding).
[[maybe_unused]] Vector6d shiftMotion(const Eigen::Vector3d& d, const Vector6d& a) {
  Vector6d out;
  out(0) = a(0) + (a(4) * d(2) - a(5) * d(1));
  out(1) = a(1) + (a(5) * d(0) - a(3) * d(2));
  out(2) = a(2) + (a(3) * d(1) - a(4) * d(0));
  out(3) = a(3);
  out(4) = a(4);
  out(5) = a(5);
  return out;
}
[[maybe_unused]] Vector6d shiftForce(const Eigen::Vector3d& d, const Vector6d& f) {
  Vector6d out = f;
  out(3) += d(1) * f(2) - d(2) * f(1);
  out(4) += d(2) * f(0) - d(0) * f(2);
  out(5) += d(0) * f(1) - d(1) * f(0);
  return out;
}
// out += shiftForce(d, f), the same operations in scalars.
[[maybe_unused]] void addShiftedForce(const Eigen::Vector3d& d, const Vector6d& f, Vector6d& out) {
  out(0) += f(0);
  out(1) += f(1);
  out(2) += f(2);
  out(3) += f(3) + (d(1) * f(2) - d(2) * f(1));
  out(4) += f(4) + (d(2) * f(0) - d(0) * f(2));
  out(5) += f(5) + (d(0) * f(1) - d(1) * f(0));
}

// Calls the pass specialized on a node's dofs (f1, f3, f6 for 1, 3, 6).
template <class F1, class F3, class F6>
void dispatch(int dofs, F1&& f1, F3&& f3, F6&& f6) {
  if (dofs == 3)
    f3();
  else if (dofs == 1)
    f1();
  else
    f6();
}

// Newton-Euler at the centre: F = M A + b, M = diag(m I, I_world), b = [-f; w x I w - t].
[[maybe_unused]] Matrix6 spatialInertia(const RigidBody& b, const Eigen::Matrix3d& inertia_world) {
  Matrix6 m = Matrix6::Zero();
  m.topLeftCorner<3, 3>().diagonal().setConstant(b.mass);
  m.bottomRightCorner<3, 3>() = inertia_world;
  return m;
}
[[maybe_unused]] Matrix6 spatialInertia(const RigidBody& b) { return spatialInertia(b, b.worldInertia()); }
[[maybe_unused]] Vector6d biasForce(const RigidBody& b, const Eigen::Matrix3d& inertia_world) {
  Vector6d out;
  out.head<3>() = -b.force;
  out.tail<3>() = b.w.cross(inertia_world * b.w) - b.torque;
  return out;
}
[[maybe_unused]] Vector6d biasForce(const RigidBody& b) { return biasForce(b, b.worldInertia()); }
// The same two, written into ABA's pass from the body's rotation r: no 6 x 6 temporary (its copy
// was a `rep movs` and a failed store forwarding per body), I_world = r I r^T by its upper
// triangle in registers.
[[maybe_unused]] void writeInertiaAndBias(const RigidBody& b, const Eigen::Matrix3d& r, Matrix6& ia, Vector6d& pa) {
  const Eigen::Matrix3d rd = r * b.inertia.asDiagonal();
  double m[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) m[i][j] = m[j][i] = rd.row(i).dot(r.row(j));
  }
  // Block by block (ia.setZero() was a `rep stos` of 288 bytes per body, then overwritten).
  ia.topLeftCorner<3, 3>().setZero();
  ia.topRightCorner<3, 3>().setZero();
  ia.bottomLeftCorner<3, 3>().setZero();
  for (int i = 0; i < 3; ++i) {
    ia(i, i) = b.mass;
    for (int j = 0; j < 3; ++j) ia(3 + i, 3 + j) = m[i][j];
  }
  const double w0 = b.w(0), w1 = b.w(1), w2 = b.w(2);
  double iw[3];
  for (int i = 0; i < 3; ++i) iw[i] = m[i][0] * w0 + m[i][1] * w1 + m[i][2] * w2;
  pa.head<3>() = -b.force;
  // w x I w - t in scalars (the cross product through a stack temporary, read back as a 16-byte
  // load of two 8-byte stores, stalled on store forwarding: 15 % of aba's samples).
  pa(3) = (w1 * iw[2] - w2 * iw[1]) - b.torque(0);
  pa(4) = (w2 * iw[0] - w0 * iw[2]) - b.torque(1);
  pa(5) = (w0 * iw[1] - w1 * iw[0]) - b.torque(2);
}

}  // namespace

}  // namespace ponyhop

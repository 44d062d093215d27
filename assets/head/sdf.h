// Signed-distance building blocks for sculpting (after Inigo Quilez's distance-function notes).
// Distances in metres, negative inside. The ellipsoid and tapered-capsule distances are the usual
// bound-like approximations: exact on the zero set's location, approximate away from it, which is
// all marching cubes and the Newton projection need.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace ponyhop::headgen {

using Vec3 = Eigen::Vector3d;

inline double sd_sphere(const Vec3& p, const Vec3& c, double r) { return (p - c).norm() - r; }

// Approximate distance to an axis-aligned ellipsoid: k0 (k0 - 1) / k1 with k0 = |q/r|, k1 = |q/r^2|.
inline double sd_ellipsoid(const Vec3& q, const Vec3& r) {
  const double k0 = q.cwiseQuotient(r).norm();
  const double k1 = q.cwiseQuotient(r.cwiseProduct(r)).norm();
  if (k1 < 1e-12) return -r.minCoeff();
  return k0 * (k0 - 1.0) / k1;
}
inline double sd_ellipsoid(const Vec3& p, const Vec3& c, const Vec3& r) { return sd_ellipsoid(p - c, r); }

// Capsule whose radius goes linearly from ra at a to rb at b (fine while |ra - rb| << |b - a|).
inline double sd_tapered_capsule(const Vec3& p, const Vec3& a, const Vec3& b, double ra, double rb) {
  const Vec3 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm() - (ra + t * (rb - ra));
}

// Torus around the local y axis: major radius R, tube radius r.
inline double sd_torus_y(const Vec3& q, double R, double r) {
  const double ring = std::hypot(q.x(), q.z()) - R;
  return std::hypot(ring, q.y()) - r;
}

// Polynomial smooth minimum: blends the two surfaces over a band of width ~k (metres).
inline double smin(double a, double b, double k) {
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::min(a, b) - h * h * k * 0.25;
}
inline double smax(double a, double b, double k) { return -smin(-a, -b, k); }
// Smoothly carve b out of a.
inline double ssub(double a, double b, double k) { return smax(a, -b, k); }

}  // namespace ponyhop::headgen

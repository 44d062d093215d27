// A head collider from any triangle mesh: its signed distance sampled on a regular grid.
//
// Why a grid SDF and not fitted spheres and capsules: the field is built automatically from any
// mesh with no fitting choices (a third-party head, a box, a sphere all go through the same code),
// its error is controlled by one number (the cell size) and measurable anywhere, a capsule
// query is a handful of trilinear samples along the link's axis, and its gradient is the contact
// normal. A sphere fit approximates the surface by bumps whose error depends on the fit and on
// how many spheres one pays for; it cannot follow a nose or a chin without many of them.
//
// Construction (Bridson's closest-triangle propagation, as in "makelevelset3"):
//   1. Distance: every grid node within one cell of a triangle's bounding box gets the exact
//      distance to that triangle (closest point on the triangle); the nearest triangle's index is
//      kept. Then 2 x 8 sweeps over the grid in the 8 diagonal orders: a node takes a neighbour's
//      nearest triangle when that one is closer (exact distance to it). Near the surface (within
//      a cell) the distance is exact; further out it is the distance to a nearby, not always the
//      nearest, triangle: an upper bound that is exact for convex parts.
//   2. Sign: inside or outside by ray parity, counted along the grid's x, y and z lines (the
//      crossings of each line with every triangle), and decided by a majority of the three: a
//      small hole or a line through an edge sways one count, not two.
// Query: trilinear interpolation of the node values (exact to O(cell^2 curvature) on smooth
// surfaces); outside the grid, the value at the nearest grid point plus the distance to it.
// The measured error against the triangles themselves: docs/PHYSICS.md, "Collisions".
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "physics/status.h"

namespace ponyhop {

class SignedDistanceGrid {
 public:
  // Builds the field of the triangles (3 indices each into `vertices`) on a grid of cubic cells
  // of edge `cell` covering the mesh's bounding box plus `padding` on every side, cut to `region`
  // when one is given (the part of a large mesh that anything can reach: the sign still counts
  // every triangle). Returns what failed (no triangles, a non-positive cell, a region that
  // misses the mesh, more than max_nodes nodes).
  Status build(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices, double cell,
               double padding, long max_nodes = 8'000'000, const Eigen::AlignedBox3d* region = nullptr);
  // The number of nodes build() would make with these inputs (0 when the region misses the mesh).
  static long nodes(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices, double cell,
                    double padding, const Eigen::AlignedBox3d* region = nullptr);

  // Signed distance (m, negative inside) and its gradient (of the interpolant, normalized).
  double distance(const Eigen::Vector3d& p) const;
  Eigen::Vector3d gradient(const Eigen::Vector3d& p) const;
  double distanceAndGradient(const Eigen::Vector3d& p, Eigen::Vector3d& gradient) const;

  double cell() const { return cell_; }
  const Eigen::Vector3d& origin() const { return origin_; }
  const Eigen::Vector3i& dims() const { return dims_; }
  Eigen::Vector3d upper() const { return origin_ + cell_ * (dims_ - Eigen::Vector3i::Ones()).cast<double>(); }
  double node(int i, int j, int k) const { return values_[index(i, j, k)]; }
  // The largest |difference| of two neighbouring nodes over the cell: each partial derivative of
  // the trilinear interpolant is an average of such differences, so the interpolant changes by at
  // most lipschitz() |dx|_1 along dx (1 for exact distances; more where a sign or a propagated
  // distance is off). The capsule search's bound (physics/shapes.h).
  double lipschitz() const { return lipschitz_; }

  // The node values (x fastest, then y, then z), and a grid made from them: what a store outside
  // the process (sim/grid_cache.h) keeps and gives back. assign refuses values that do not fill
  // the dims, a non-positive cell and non-finite numbers.
  const std::vector<float>& values() const { return values_; }
  Status assign(const Eigen::Vector3d& origin, const Eigen::Vector3i& dims, double cell, double lipschitz,
                std::vector<float> values);

 private:
  size_t index(int i, int j, int k) const { return (static_cast<size_t>(k) * dims_.y() + j) * dims_.x() + i; }
  double trilinear(const Eigen::Vector3d& p, Eigen::Vector3d* grad) const;

  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  double cell_ = 0.0;
  double lipschitz_ = 0.0;
  std::vector<float> values_;
};

// Inline, so that distance() (the searches' samples, no gradient) is compiled without the
// gradient's branch. Written out per axis on scalars (the Eigen 3-vector version spent a third of its time in
// temporaries); every value is the same operation in the same order as before, so the results are
// the same bit for bit: clamping as max(rel, 0) then min(., top), the cell's origin node, the
// fractions, seven lerps and, on request, the interpolant's gradient.
inline double SignedDistanceGrid::trilinear(const Eigen::Vector3d& p, Eigen::Vector3d* grad) const {
  double rel[3], clamped[3], f[3];
  int i0[3];
  bool inside = true;
  for (int a = 0; a < 3; ++a) {
    rel[a] = (p[a] - origin_[a]) / cell_;
    const double top = static_cast<double>(dims_[a] - 1);
    const double lo = rel[a] > 0.0 ? rel[a] : 0.0;  // max(rel, 0): 0 when equal, like maxsd
    clamped[a] = lo < top ? lo : top;
    inside = inside && rel[a] == clamped[a];
    // clamped >= 0, where truncation is the floor (std::floor is a call without SSE4.1).
    i0[a] = std::min(static_cast<int>(clamped[a]), dims_[a] - 2);
    f[a] = clamped[a] - i0[a];
  }
  // The cell's 8 nodes from its lowest one by the strides of y and z (x is contiguous).
  const size_t sy = static_cast<size_t>(dims_.x()), sz = sy * static_cast<size_t>(dims_.y());
  const float* v = values_.data() + index(i0[0], i0[1], i0[2]);
  const double c000 = v[0], c100 = v[1], c010 = v[sy], c110 = v[sy + 1];
  const double c001 = v[sz], c101 = v[sz + 1], c011 = v[sz + sy], c111 = v[sz + sy + 1];
  const double x = f[0], y = f[1], z = f[2];
  const auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
  const double c00 = lerp(c000, c100, x), c10 = lerp(c010, c110, x);
  const double c01 = lerp(c001, c101, x), c11 = lerp(c011, c111, x);
  const double c0 = lerp(c00, c10, y), c1 = lerp(c01, c11, y);
  const double value = lerp(c0, c1, z);
  // Inside the grid (the common case) nothing is added and no square root is taken; beyond it,
  // plus the distance to it.
  if (inside) {
    if (grad) {
      const double gx = lerp(lerp(c100 - c000, c110 - c010, y), lerp(c101 - c001, c111 - c011, y), z);
      const double gy = lerp(lerp(c010 - c000, c110 - c100, x), lerp(c011 - c001, c111 - c101, x), z);
      const double gz = c1 - c0;
      const Eigen::Vector3d g(gx, gy, gz);
      const double n = g.norm();
      *grad = n > 0.0 ? Eigen::Vector3d(g / n) : Eigen::Vector3d::UnitZ();
    }
    return value;
  }
  const Eigen::Vector3d outside =
      Eigen::Vector3d(rel[0] - clamped[0], rel[1] - clamped[1], rel[2] - clamped[2]) * cell_;
  const double out = outside.norm();
  if (grad) *grad = outside / out;  // beyond the grid: away from it
  return value + out;
}

inline double SignedDistanceGrid::distance(const Eigen::Vector3d& p) const { return trilinear(p, nullptr); }

// Where the line {x_u = pu, x_v = pv} along axis a (u = a + 1, v = a + 2, mod 3) crosses the
// triangle p0 p1 p2: true and the crossing's coordinate along a in `at`, or false.
bool lineCrossesTriangle(int a, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                         double pu, double pv, double& at);

// Exact signed distance from p to a closed triangle mesh by brute force over every triangle, the
// sign by ray parity (majority of the +x, +y, +z rays). For tests and measurements: O(triangles).
double signedDistanceToTriangles(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices,
                                 const Eigen::Vector3d& p);

}  // namespace ponyhop

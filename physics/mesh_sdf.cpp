#include "physics/mesh_sdf.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "physics/shapes.h"

namespace ponyhop {

// Where the line {x_u = pu, x_v = pv} (along axis a) crosses the triangle, or false.
bool lineCrossesTriangle(int a, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                         double pu, double pv, double& at) {
  const int u = (a + 1) % 3, v = (a + 2) % 3;
  const double e1u = p1(u) - p0(u), e1v = p1(v) - p0(v), e2u = p2(u) - p0(u), e2v = p2(v) - p0(v);
  const double d = e1u * e2v - e1v * e2u;
  if (std::abs(d) < 1e-30) return false;  // edge-on to the line
  const double qu = pu - p0(u), qv = pv - p0(v);
  const double w1 = (qu * e2v - qv * e2u) / d;
  const double w2 = (e1u * qv - e1v * qu) / d;
  if (w1 < 0.0 || w2 < 0.0 || w1 + w2 > 1.0) return false;
  at = p0(a) + w1 * (p1(a) - p0(a)) + w2 * (p2(a) - p0(a));
  return true;
}

namespace {

// The grid's box: the mesh's bounds (indices checked in range) plus the padding, cut to the region;
// false when the region leaves less than a cell on some side.
bool gridBox(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices, double cell,
             double padding, const Eigen::AlignedBox3d* region, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
  lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  hi = -lo;
  for (uint32_t i : indices) {
    lo = lo.cwiseMin(vertices[i]);
    hi = hi.cwiseMax(vertices[i]);
  }
  lo.array() -= padding;
  hi.array() += padding;
  if (region) {
    lo = lo.cwiseMax(region->min());
    hi = hi.cwiseMin(region->max());
    // At least two nodes a side (trilinear interpolation needs a cell).
    if (((hi - lo).array() < cell).any()) return false;
  }
  return true;
}

Eigen::Vector3i gridDims(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double cell) {
  Eigen::Vector3i dims;
  for (int a = 0; a < 3; ++a) dims(a) = static_cast<int>(std::ceil((hi(a) - lo(a)) / cell)) + 1;
  return dims;
}

}  // namespace

long SignedDistanceGrid::nodes(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices,
                               double cell, double padding, const Eigen::AlignedBox3d* region) {
  Eigen::Vector3d lo, hi;
  if (indices.empty() || !gridBox(vertices, indices, cell, padding, region, lo, hi)) return 0;
  const Eigen::Vector3i dims = gridDims(lo, hi, cell);
  return static_cast<long>(dims.x()) * dims.y() * dims.z();
}

Status SignedDistanceGrid::build(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices,
                                 double cell, double padding, long max_nodes, const Eigen::AlignedBox3d* region) {
  const size_t tris = indices.size() / 3;
  if (tris == 0) return Status::error("collider mesh has no triangles");
  if (!(cell > 0.0) || !std::isfinite(cell)) return Status::error("collider cell must be positive (m)");
  for (uint32_t i : indices)
    if (i >= vertices.size()) return Status::error("collider mesh: a triangle index is out of range");
  Eigen::Vector3d lo, hi;
  if (!gridBox(vertices, indices, cell, padding, region, lo, hi))
    return Status::error("collider region does not meet the mesh");
  cell_ = cell;
  origin_ = lo;
  dims_ = gridDims(lo, hi, cell);
  const long nodes = static_cast<long>(dims_.x()) * dims_.y() * dims_.z();
  if (nodes > max_nodes) {
    return Status::error("collider grid of " + std::to_string(nodes) + " nodes is larger than " +
                         std::to_string(max_nodes) + ": raise the cell size");
  }
  const auto vert = [&](size_t t, int k) -> const Eigen::Vector3d& { return vertices[indices[3 * t + k]]; };
  const auto nodeAt = [&](int i, int j, int k) -> Eigen::Vector3d {
    return origin_ + cell_ * Eigen::Vector3d(i, j, k);
  };

  // 1. Distance: exact near each triangle, then closest-triangle propagation.
  std::vector<double> dist(nodes, std::numeric_limits<double>::infinity());
  std::vector<int> nearest(nodes, -1);
  for (size_t t = 0; t < tris; ++t) {
    Eigen::Vector3d tlo = vert(t, 0).cwiseMin(vert(t, 1)).cwiseMin(vert(t, 2));
    Eigen::Vector3d thi = vert(t, 0).cwiseMax(vert(t, 1)).cwiseMax(vert(t, 2));
    // A triangle more than a cell outside the grid seeds no node (the propagation brings the
    // distances in from the triangles near the grid).
    if (((tlo - hi).array() > cell_).any() || ((lo - thi).array() > cell_).any()) continue;
    Eigen::Vector3i ilo, ihi;
    for (int a = 0; a < 3; ++a) {
      ilo(a) = std::clamp(static_cast<int>(std::floor((tlo(a) - origin_(a)) / cell_)) - 1, 0, dims_(a) - 1);
      ihi(a) = std::clamp(static_cast<int>(std::ceil((thi(a) - origin_(a)) / cell_)) + 1, 0, dims_(a) - 1);
    }
    for (int k = ilo.z(); k <= ihi.z(); ++k)
      for (int j = ilo.y(); j <= ihi.y(); ++j)
        for (int i = ilo.x(); i <= ihi.x(); ++i) {
          const Eigen::Vector3d p = nodeAt(i, j, k);
          const double d = (p - closestPointOnTriangle(p, vert(t, 0), vert(t, 1), vert(t, 2))).norm();
          const size_t n = index(i, j, k);
          if (d < dist[n]) {
            dist[n] = d;
            nearest[n] = static_cast<int>(t);
          }
        }
  }
  // The sweeps offer a node the same few triangles again and again (its neighbours share them):
  // each node remembers the last two it has tried and lost to its nearest (rejected, or replaced
  // by a closer one). Skipping them is exact: the distance to a triangle does not change and the
  // node's own distance only falls, so a triangle that lost once loses again. A third of the
  // closest-point evaluations go (the head: 13.7 -> 8.9 million).
  std::vector<std::array<int, 2>> lost(nodes, {-1, -1});
  const auto tryNeighbour = [&](size_t n, const Eigen::Vector3d& p, size_t m) {
    const int t = nearest[m];
    if (t < 0 || t == nearest[n] || t == lost[n][0] || t == lost[n][1]) return;
    const double d = (p - closestPointOnTriangle(p, vert(t, 0), vert(t, 1), vert(t, 2))).norm();
    const int loser = d < dist[n] ? nearest[n] : t;
    if (d < dist[n]) {
      dist[n] = d;
      nearest[n] = t;
    }
    if (loser >= 0) lost[n] = {loser, lost[n][0]};
  };
  for (int pass = 0; pass < 2; ++pass)
    for (int dir = 0; dir < 8; ++dir) {
      const int di = (dir & 1) ? -1 : 1, dj = (dir & 2) ? -1 : 1, dk = (dir & 4) ? -1 : 1;
      for (int kk = 0; kk < dims_.z(); ++kk) {
        const int k = dk > 0 ? kk : dims_.z() - 1 - kk;
        for (int jj = 0; jj < dims_.y(); ++jj) {
          const int j = dj > 0 ? jj : dims_.y() - 1 - jj;
          for (int ii = 0; ii < dims_.x(); ++ii) {
            const int i = di > 0 ? ii : dims_.x() - 1 - ii;
            const size_t n = index(i, j, k);
            const Eigen::Vector3d p = nodeAt(i, j, k);
            if (i - di >= 0 && i - di < dims_.x()) tryNeighbour(n, p, index(i - di, j, k));
            if (j - dj >= 0 && j - dj < dims_.y()) tryNeighbour(n, p, index(i, j - dj, k));
            if (k - dk >= 0 && k - dk < dims_.z()) tryNeighbour(n, p, index(i, j, k - dk));
          }
        }
      }
    }

  // 2. Sign: crossings along the grid lines of each axis; a node is inside when most of the
  // three lines through it have an odd number of crossings before it.
  std::vector<unsigned char> votes(nodes, 0);
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    std::vector<std::vector<double>> lines(static_cast<size_t>(dims_(u)) * dims_(v));
    for (size_t t = 0; t < tris; ++t) {
      const Eigen::Vector3d tlo = vert(t, 0).cwiseMin(vert(t, 1)).cwiseMin(vert(t, 2));
      const Eigen::Vector3d thi = vert(t, 0).cwiseMax(vert(t, 1)).cwiseMax(vert(t, 2));
      const int u0 = std::max(0, static_cast<int>(std::ceil((tlo(u) - origin_(u)) / cell_)));
      const int u1 = std::min(dims_(u) - 1, static_cast<int>(std::floor((thi(u) - origin_(u)) / cell_)));
      const int v0 = std::max(0, static_cast<int>(std::ceil((tlo(v) - origin_(v)) / cell_)));
      const int v1 = std::min(dims_(v) - 1, static_cast<int>(std::floor((thi(v) - origin_(v)) / cell_)));
      for (int iv = v0; iv <= v1; ++iv)
        for (int iu = u0; iu <= u1; ++iu) {
          double at = 0.0;
          if (lineCrossesTriangle(a, vert(t, 0), vert(t, 1), vert(t, 2), origin_(u) + cell_ * iu,
                                  origin_(v) + cell_ * iv, at))
            lines[static_cast<size_t>(iv) * dims_(u) + iu].push_back(at);
        }
    }
    for (int iv = 0; iv < dims_(v); ++iv)
      for (int iu = 0; iu < dims_(u); ++iu) {
        std::vector<double>& c = lines[static_cast<size_t>(iv) * dims_(u) + iu];
        std::sort(c.begin(), c.end());
        size_t passed = 0;
        for (int ia = 0; ia < dims_(a); ++ia) {
          const double x = origin_(a) + cell_ * ia;
          while (passed < c.size() && c[passed] < x) ++passed;
          Eigen::Vector3i idx;
          idx(a) = ia;
          idx(u) = iu;
          idx(v) = iv;
          if (passed % 2 == 1) ++votes[index(idx.x(), idx.y(), idx.z())];
        }
      }
  }
  values_.resize(nodes);
  for (long n = 0; n < nodes; ++n) values_[n] = static_cast<float>(votes[n] >= 2 ? -dist[n] : dist[n]);
  double steepest = 0.0;
  for (int k = 0; k < dims_.z(); ++k)
    for (int j = 0; j < dims_.y(); ++j)
      for (int i = 0; i < dims_.x(); ++i) {
        const double v = values_[index(i, j, k)];
        if (i + 1 < dims_.x()) steepest = std::max(steepest, std::abs(values_[index(i + 1, j, k)] - v));
        if (j + 1 < dims_.y()) steepest = std::max(steepest, std::abs(values_[index(i, j + 1, k)] - v));
        if (k + 1 < dims_.z()) steepest = std::max(steepest, std::abs(values_[index(i, j, k + 1)] - v));
      }
  lipschitz_ = steepest / cell_;
  return {};
}

Status SignedDistanceGrid::assign(const Eigen::Vector3d& origin, const Eigen::Vector3i& dims, double cell,
                                  double lipschitz, std::vector<float> values) {
  if (!origin.allFinite() || !(cell > 0.0) || !std::isfinite(cell) || !std::isfinite(lipschitz) || lipschitz < 0.0)
    return Status::error("distance grid: origin, cell or Lipschitz bound out of range");
  if ((dims.array() < 2).any()) return Status::error("distance grid: fewer than two nodes a side");
  const double nodes = static_cast<double>(dims.x()) * dims.y() * dims.z();
  if (nodes != static_cast<double>(values.size())) return Status::error("distance grid: the values do not fill it");
  for (float v : values)
    if (!std::isfinite(v)) return Status::error("distance grid: a value is not a number");
  origin_ = origin;
  dims_ = dims;
  cell_ = cell;
  lipschitz_ = lipschitz;
  values_ = std::move(values);
  return {};
}

Eigen::Vector3d SignedDistanceGrid::gradient(const Eigen::Vector3d& p) const {
  Eigen::Vector3d g;
  trilinear(p, &g);
  return g;
}

double SignedDistanceGrid::distanceAndGradient(const Eigen::Vector3d& p, Eigen::Vector3d& gradient) const {
  return trilinear(p, &gradient);
}

double signedDistanceToTriangles(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices,
                                 const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  std::array<int, 3> crossings{0, 0, 0};
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const Eigen::Vector3d& a = vertices[indices[t]];
    const Eigen::Vector3d& b = vertices[indices[t + 1]];
    const Eigen::Vector3d& c = vertices[indices[t + 2]];
    best = std::min(best, (p - closestPointOnTriangle(p, a, b, c)).norm());
    for (int ax = 0; ax < 3; ++ax) {
      double at = 0.0;
      if (lineCrossesTriangle(ax, a, b, c, p((ax + 1) % 3), p((ax + 2) % 3), at) && at > p(ax)) ++crossings[ax];
    }
  }
  const int odd = (crossings[0] % 2) + (crossings[1] % 2) + (crossings[2] % 2);
  return odd >= 2 ? -best : best;
}

}  // namespace ponyhop

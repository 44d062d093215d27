#include "physics/triangle_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "physics/mesh_sdf.h"
#include "physics/shapes.h"

namespace ponyhop {

TriangleDistance::TriangleDistance(std::vector<Eigen::Vector3d> vertices, std::vector<uint32_t> indices, double cell,
                                   double reach)
    : vertices_(std::move(vertices)), indices_(std::move(indices)), cell_(cell), reach_(reach) {
  lo_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  hi_ = -lo_;
  for (uint32_t i : indices_) {
    lo_ = lo_.cwiseMin(vertices_[i]);
    hi_ = hi_.cwiseMax(vertices_[i]);
  }
  fill(near_, -1, reach_);
  for (int a = 0; a < 3; ++a) fill(rays_[size_t(a)], a, 0.0);
}

long TriangleDistance::Buckets::cellOf(const Eigen::Vector3d& p, double cell) const {
  long index = 0;
  for (int k = 2; k >= 0; --k) {
    if (dims(k) == 1) continue;  // the axis a ray grid does not divide
    const double c = std::floor((p(k) - origin(k)) / cell);
    if (!(c >= 0.0 && c < dims(k))) return -1;
    index = index * dims(k) + static_cast<long>(c);
  }
  return index;
}

void TriangleDistance::fill(Buckets& b, int flat, double grow) const {
  const size_t tris = indices_.size() / 3;
  if (tris == 0) return;
  b.origin = lo_ - Eigen::Vector3d::Constant(grow);
  for (int k = 0; k < 3; ++k)
    b.dims(k) = k == flat ? 1 : static_cast<int>(std::floor((hi_(k) + grow - b.origin(k)) / cell_)) + 1;
  // The cells a triangle's grown box covers: [c0, c1] per axis (the flat axis: [0, 0]).
  auto range = [&](size_t t, Eigen::Vector3i& c0, Eigen::Vector3i& c1) {
    const Eigen::Vector3d tlo = vertex(t, 0).cwiseMin(vertex(t, 1)).cwiseMin(vertex(t, 2));
    const Eigen::Vector3d thi = vertex(t, 0).cwiseMax(vertex(t, 1)).cwiseMax(vertex(t, 2));
    for (int k = 0; k < 3; ++k) {
      if (k == flat) {
        c0(k) = c1(k) = 0;
        continue;
      }
      c0(k) = std::clamp(static_cast<int>(std::floor((tlo(k) - grow - b.origin(k)) / cell_)), 0, b.dims(k) - 1);
      c1(k) = std::clamp(static_cast<int>(std::floor((thi(k) + grow - b.origin(k)) / cell_)), 0, b.dims(k) - 1);
    }
  };
  auto forEachCell = [&](size_t t, auto&& visit) {
    Eigen::Vector3i c0, c1;
    range(t, c0, c1);
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x) visit((static_cast<size_t>(z) * b.dims.y() + y) * b.dims.x() + x);
  };
  // Two passes: count each cell's triangles, then place them (one flat array, no list per cell).
  const size_t cells = static_cast<size_t>(b.dims.x()) * b.dims.y() * b.dims.z();
  b.first.assign(cells + 1, 0);
  for (size_t t = 0; t < tris; ++t) forEachCell(t, [&](size_t c) { ++b.first[c + 1]; });
  for (size_t c = 0; c < cells; ++c) b.first[c + 1] += b.first[c];
  b.list.resize(b.first[cells]);
  std::vector<uint32_t> next(b.first.begin(), b.first.end() - 1);
  for (size_t t = 0; t < tris; ++t) forEachCell(t, [&](size_t c) { b.list[next[c]++] = static_cast<uint32_t>(t); });
}

bool TriangleDistance::inside(const Eigen::Vector3d& p) const {
  int odd = 0;
  for (int a = 0; a < 3; ++a) {
    const Buckets& b = rays_[size_t(a)];
    const long c = b.cellOf(p, cell_);
    if (c < 0) continue;  // beside the mesh's bounds: the ray meets nothing
    int crossings = 0;
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    for (uint32_t i = b.first[size_t(c)]; i < b.first[size_t(c) + 1]; ++i) {
      const size_t t = b.list[i];
      double at = 0.0;
      if (lineCrossesTriangle(a, vertex(t, 0), vertex(t, 1), vertex(t, 2), p(u), p(v), at) && at > p(a)) ++crossings;
    }
    odd += crossings % 2;
  }
  return odd >= 2;
}

double TriangleDistance::signedDistance(const Eigen::Vector3d& p) const {
  double best = reach_;
  const long c = near_.cellOf(p, cell_);
  if (c >= 0) {
    for (uint32_t i = near_.first[size_t(c)]; i < near_.first[size_t(c) + 1]; ++i) {
      const size_t t = near_.list[i];
      best = std::min(best, (p - closestPointOnTriangle(p, vertex(t, 0), vertex(t, 1), vertex(t, 2))).norm());
    }
  }
  return inside(p) ? -best : best;
}

}  // namespace ponyhop

#include "engine/primitives.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ponyhop {

HullTemplate makeHullTemplate(int slices, int rings) {
  slices = std::max(slices, 3);
  rings = std::max(rings, 1);
  HullTemplate h;
  const int row = slices + 1;  // the seam vertex is duplicated (same position; keeps indexing simple)
  for (int cap = 0; cap < 2; ++cap)
    for (int k = 0; k <= rings; ++k)
      for (int j = 0; j <= slices; ++j) {
        const double a = 2.0 * std::numbers::pi * double(j % slices) / double(slices);
        h.vertices.push_back({float(std::cos(a)), float(std::sin(a)), float(k) / float(rings), float(cap)});
      }
  // Rows in order of rising elevation: cap 0 rings 0..rings, then cap 1 rings 0..rings. Quads
  // between consecutive rows; the quad strip between cap 0's last ring and cap 1's first ring is
  // the tangent cone. Counter-clockwise seen from outside ((u, v, w) is right-handed).
  const int rows = 2 * (rings + 1);
  for (int r = 0; r + 1 < rows; ++r)
    for (int j = 0; j < slices; ++j) {
      const uint32_t a = uint32_t(r * row + j), b = a + 1, c = a + uint32_t(row), d = c + 1;
      // Row 0 and the last row are the poles (all of a row's vertices coincide): skip the
      // triangle that would be degenerate there.
      if (r != 0) h.indices.insert(h.indices.end(), {a, b, d});
      if (r + 2 != rows) h.indices.insert(h.indices.end(), {a, d, c});
    }
  return h;
}

Eigen::AlignedBox3d hullBounds(const Eigen::Vector3d& p0, double r0, const Eigen::Vector3d& p1, double r1) {
  Eigen::AlignedBox3d b;
  b.extend(p0 - Eigen::Vector3d::Constant(r0));
  b.extend(p0 + Eigen::Vector3d::Constant(r0));
  b.extend(p1 - Eigen::Vector3d::Constant(r1));
  b.extend(p1 + Eigen::Vector3d::Constant(r1));
  return b;
}

Eigen::AlignedBox3d transformedBounds(const Eigen::Affine3d& T, const Eigen::AlignedBox3d& local) {
  Eigen::AlignedBox3d b;
  if (local.isEmpty()) return b;
  for (int i = 0; i < 8; ++i) b.extend(T * local.corner(Eigen::AlignedBox3d::CornerType(i)));
  return b;
}

}  // namespace ponyhop

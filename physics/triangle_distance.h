// The exact signed distance from points to a closed triangle mesh, for tests and measurements that
// check the collider against the triangles themselves (not against its grid).
//
// The same answer as signedDistanceToTriangles (mesh_sdf.h: closest point over the triangles,
// sign by the majority of the +x, +y, +z ray parities), without visiting every triangle:
//   - distance: each triangle is listed in every cell of a uniform grid that its bounding box,
//     grown by `reach`, overlaps; a triangle within `reach` of p then lies in p's own cell, so the
//     nearest one is found among that cell's few;
//   - sign: for each axis, each triangle is listed in every cell of a 2D grid (the other two
//     coordinates) that its projected bounding box overlaps; the ray from p along the axis can
//     only cross the triangles of the cell it starts in.
// A box head of 12 triangles, 1 m across, costs a few dozen triangle tests per point instead of a
// search of millions of empty buckets; a 30,000-triangle head, a few hundred instead of 30,000.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace ponyhop {

class TriangleDistance {
 public:
  // `cell` (m) sizes the buckets; `reach` (m) is how far the exact distance is needed.
  TriangleDistance(std::vector<Eigen::Vector3d> vertices, std::vector<uint32_t> indices, double cell, double reach);

  // The exact signed distance (negative inside) when it is within `reach` of the surface; farther
  // away a value of the right sign whose size is at least `reach`.
  double signedDistance(const Eigen::Vector3d& p) const;
  // Inside by the majority of the three ray parities (signedDistanceToTriangles' rule).
  bool inside(const Eigen::Vector3d& p) const;

 private:
  // Triangles listed per cell of a 2D or 3D grid, in one flat array (cells' lists back to back).
  struct Buckets {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Eigen::Vector3i dims = Eigen::Vector3i::Ones();
    std::vector<uint32_t> first;  // cell c's triangles: list[first[c] .. first[c + 1])
    std::vector<uint32_t> list;
    long cellOf(const Eigen::Vector3d& p, double cell) const;  // -1 outside
  };
  // Fills b with every triangle over the cells its box (lo - grow .. hi + grow) overlaps; `flat`
  // is the axis the grid does not divide (-1: a 3D grid).
  void fill(Buckets& b, int flat, double grow) const;
  const Eigen::Vector3d& vertex(size_t t, int k) const { return vertices_[indices_[3 * t + k]]; }

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<uint32_t> indices_;
  double cell_;
  double reach_;
  Eigen::Vector3d lo_, hi_;  // the mesh's bounds
  Buckets near_;
  std::array<Buckets, 3> rays_;
};

}  // namespace ponyhop

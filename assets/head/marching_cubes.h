// Marching cubes over a regular grid of signed-distance samples (negative inside).
//
// The case table (256 sign patterns -> triangles) is derived at start-up rather than typed in:
// on every cube face the iso-contour is a set of segments between sign-change edges; chaining the
// segments of all six faces gives closed loops on the cube surface, and each loop is fanned into
// triangles. Ambiguous faces (two diagonal corners inside) are always resolved the same way
// ("inside corners stay separate"), and that decision depends only on the face's own four signs,
// so two cells sharing a face cut it identically and the mesh is watertight.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace ponyhop::headgen {

struct TriMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

struct Grid {
  Eigen::Vector3d origin;      // position of sample (0,0,0), metres
  double cell = 0.0;           // spacing, metres
  int nx = 0, ny = 0, nz = 0;  // samples per axis
};

// One triangle list per sign pattern; triangle corners are cube-edge ids 0..11.
// Bit i of the pattern is set when corner i (x = i&1, y = (i>>1)&1, z = (i>>2)&1) is inside.
using CaseTable = std::array<std::vector<std::array<int, 3>>, 256>;
const CaseTable& marching_cubes_table();

// The two corners joined by cube edge e.
std::array<int, 2> cube_edge_corners(int e);

// Polygonises the zero set of `sdf` on `grid`. Vertices are welded by grid edge (each grid edge
// crossing becomes exactly one vertex) and placed by linear interpolation. Normals are left empty.
TriMesh marching_cubes(const Grid& grid, const std::function<double(const Eigen::Vector3d&)>& sdf);

}  // namespace ponyhop::headgen

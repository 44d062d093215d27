#include "marching_cubes.h"

#include <map>

namespace ponyhop::headgen {
namespace {

// Corner index c = x + 2y + 4z. Edge id = axis * 4 + k, where k enumerates the two other bits.
std::array<std::array<int, 2>, 12> make_edges() {
  std::array<std::array<int, 2>, 12> edges{};
  for (int axis = 0; axis < 3; ++axis) {
    const int bit = 1 << axis;
    int k = 0;
    for (int c = 0; c < 8; ++c) {
      if (c & bit) continue;
      edges[static_cast<std::size_t>(axis * 4 + k)] = {c, c | bit};
      ++k;
    }
  }
  return edges;
}

const std::array<std::array<int, 2>, 12> kEdges = make_edges();

int edge_between(int a, int b) {
  for (int e = 0; e < 12; ++e) {
    const auto& ed = kEdges[static_cast<std::size_t>(e)];
    if ((ed[0] == a && ed[1] == b) || (ed[0] == b && ed[1] == a)) return e;
  }
  return -1;
}

// The six faces, each as four corners in counter-clockwise order seen from outside the cube.
std::array<std::array<int, 4>, 6> make_faces() {
  std::array<std::array<int, 4>, 6> faces{};
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      // (0,0) -> (1,0) -> (1,1) -> (0,1) in (u, v) turns counter-clockwise about +axis, because
      // e_u x e_v = e_axis for cyclic (axis, u, v). The face at side 0 looks along -axis: reverse.
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      std::array<int, 4> f{};
      for (int i = 0; i < 4; ++i) {
        f[static_cast<std::size_t>(i)] = (side << axis) | (uv[i][0] << u) | (uv[i][1] << v);
      }
      if (side == 0) std::swap(f[1], f[3]);
      faces[static_cast<std::size_t>(axis * 2 + side)] = f;
    }
  }
  return faces;
}

CaseTable make_table() {
  const auto faces = make_faces();
  CaseTable table;
  for (int pattern = 0; pattern < 256; ++pattern) {
    auto inside = [pattern](int c) { return ((pattern >> c) & 1) != 0; };
    // next[x] = y: the contour on some face runs from the crossing on edge x to the one on edge y.
    std::array<int, 12> next;
    next.fill(-1);
    for (const auto& f : faces) {
      // Crossings in counter-clockwise order around the face; "exit" = walking from an inside
      // corner to an outside one.
      int edge[4], n = 0;
      bool exit[4];
      for (int i = 0; i < 4; ++i) {
        const int a = f[static_cast<std::size_t>(i)], b = f[static_cast<std::size_t>((i + 1) % 4)];
        if (inside(a) == inside(b)) continue;
        edge[n] = edge_between(a, b);
        exit[n] = inside(a);
        ++n;
      }
      // Each inside region of the face is bounded by entry -> inside corners -> exit -> contour
      // segment -> entry (counter-clockwise), so the segment joins each exit to the crossing just
      // before it. With four crossings this keeps the two inside corners apart (our fixed rule).
      for (int i = 0; i < n; ++i) {
        if (exit[i]) next[static_cast<std::size_t>(edge[i])] = edge[(i + n - 1) % n];
      }
    }
    // Chain the segments into loops. Walking a loop, the inside lies on the left seen from outside
    // the cube, i.e. the loop turns counter-clockwise about the direction pointing *into* the
    // solid. Fanning it in reverse order gives triangles whose normals point out of the solid.
    std::array<bool, 12> used{};
    for (int start = 0; start < 12; ++start) {
      if (next[static_cast<std::size_t>(start)] < 0 || used[static_cast<std::size_t>(start)]) continue;
      std::vector<int> loop;
      for (int e = start; !used[static_cast<std::size_t>(e)]; e = next[static_cast<std::size_t>(e)]) {
        used[static_cast<std::size_t>(e)] = true;
        loop.push_back(e);
      }
      for (std::size_t i = 1; i + 1 < loop.size(); ++i) {
        table[static_cast<std::size_t>(pattern)].push_back({loop[0], loop[i + 1], loop[i]});
      }
    }
  }
  return table;
}

}  // namespace

const CaseTable& marching_cubes_table() {
  static const CaseTable table = make_table();
  return table;
}

std::array<int, 2> cube_edge_corners(int e) { return kEdges[static_cast<std::size_t>(e)]; }

TriMesh marching_cubes(const Grid& grid, const std::function<double(const Eigen::Vector3d&)>& sdf) {
  const CaseTable& table = marching_cubes_table();
  const long nx = grid.nx, ny = grid.ny, nz = grid.nz;
  auto index = [&](long i, long j, long k) { return static_cast<std::size_t>((k * ny + j) * nx + i); };
  auto point = [&](long i, long j, long k) {
    return Eigen::Vector3d(grid.origin + grid.cell * Eigen::Vector3d(double(i), double(j), double(k)));
  };

  std::vector<double> value(static_cast<std::size_t>(nx * ny * nz));
  for (long k = 0; k < nz; ++k)
    for (long j = 0; j < ny; ++j)
      for (long i = 0; i < nx; ++i) value[index(i, j, k)] = sdf(point(i, j, k));

  // One vertex per crossed grid edge, found by (lower grid point, axis): this is the weld.
  std::array<std::vector<std::int32_t>, 3> edge_vertex;
  for (auto& ev : edge_vertex) ev.assign(value.size(), -1);

  TriMesh mesh;
  auto vertex_on = [&](long i, long j, long k, int axis) -> std::uint32_t {
    std::int32_t& slot = edge_vertex[static_cast<std::size_t>(axis)][index(i, j, k)];
    if (slot < 0) {
      const long i1 = i + (axis == 0), j1 = j + (axis == 1), k1 = k + (axis == 2);
      const double f0 = value[index(i, j, k)], f1 = value[index(i1, j1, k1)];
      const double t = f0 / (f0 - f1);  // signs differ, so f0 != f1
      mesh.positions.push_back(point(i, j, k) + t * (point(i1, j1, k1) - point(i, j, k)));
      slot = static_cast<std::int32_t>(mesh.positions.size() - 1);
    }
    return static_cast<std::uint32_t>(slot);
  };

  for (long k = 0; k + 1 < nz; ++k) {
    for (long j = 0; j + 1 < ny; ++j) {
      for (long i = 0; i + 1 < nx; ++i) {
        int pattern = 0;
        for (int c = 0; c < 8; ++c) {
          if (value[index(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))] < 0.0) pattern |= 1 << c;
        }
        for (const auto& tri : table[static_cast<std::size_t>(pattern)]) {
          std::array<std::uint32_t, 3> t{};
          for (int m = 0; m < 3; ++m) {
            const int e = tri[static_cast<std::size_t>(m)];
            const int c0 = kEdges[static_cast<std::size_t>(e)][0];
            t[static_cast<std::size_t>(m)] = vertex_on(i + (c0 & 1), j + ((c0 >> 1) & 1), k + ((c0 >> 2) & 1), e / 4);
          }
          mesh.triangles.push_back(t);
        }
      }
    }
  }
  return mesh;
}

}  // namespace ponyhop::headgen

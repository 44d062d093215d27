// The shadow pass's simplified copies of large meshes (shadowLevels, shadowRange): each within its
// error of the surface and wound as the mesh, and a frame's texel picks the coarsest within it.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tuple>

#include "engine/mesh.h"
#include "engine/renderer_impl.h"

using namespace ponyhop;

namespace {

// A UV sphere with its seam and pole vertices merged (one vertex per position), closed as the
// default head's mesh is: its faces only, no duplicated vertices at a seam.
MeshData weldedSphere(int slices, int stacks) {
  const MeshData uv = makeUvSphere(1.0f, slices, stacks);
  MeshData m;
  std::map<std::tuple<float, float, float>, uint32_t> index;
  std::vector<uint32_t> remap;
  for (const Eigen::Vector3f& p : uv.positions) {
    const auto [it, added] = index.try_emplace({p.x(), p.y(), p.z()}, uint32_t(m.positions.size()));
    if (added) m.positions.push_back(p);
    remap.push_back(it->second);
  }
  m.normals = m.positions;
  for (uint32_t i : uv.indices) m.indices.push_back(remap[i]);
  m.computeBounds();
  return m;
}

}  // namespace

TEST(ShadowLevels, EachLevelIsCoarserAndWithinItsErrorOfTheSphere) {
  const MeshData sphere = weldedSphere(128, 80);  // 20,224 triangles
  ASSERT_GE(sphere.triangleCount(), 8192u);
  std::vector<uint32_t> indices = sphere.indices;
  const std::vector<GpuMesh::ShadowLevel> levels = shadowLevels(sphere, indices);
  ASSERT_GE(levels.size(), 3u);
  // Farther than the mesh's own faces are inside the sphere (its chords span at most pi / 80).
  const double sag = 1.0 - std::cos(M_PI / 80.0);
  uint32_t end = uint32_t(sphere.indices.size()), previous = end;
  float previous_error = 0.0f;
  for (const GpuMesh::ShadowLevel& l : levels) {
    EXPECT_EQ(l.first, end);  // after the mesh's indices and the level before
    EXPECT_LT(l.count, previous);
    EXPECT_GT(l.error, previous_error);
    ASSERT_EQ(l.count % 3, 0u);
    int flipped = 0;
    for (uint32_t t = l.first; t < l.first + l.count; t += 3) {
      const Eigen::Vector3d a = sphere.positions[indices[t]].cast<double>();
      const Eigen::Vector3d b = sphere.positions[indices[t + 1]].cast<double>();
      const Eigen::Vector3d c = sphere.positions[indices[t + 2]].cast<double>();
      const Eigen::Vector3d centroid = (a + b + c) / 3.0;
      // The vertices are the sphere's, so the face's farthest point from it is near its centroid.
      // The error is meshoptimizer's quadric estimate (distance to the planes of the faces
      // collapsed into a vertex), not a bound: the faces lie up to 2.6 times as far from this
      // sphere (its 11,193-triangle level).
      ASSERT_LE(1.0 - centroid.norm() - sag, 3.0 * l.error) << "level of error " << l.error;
      // Wound as the mesh (outward): the shadow pass culls the same faces. A few slivers fold
      // over (4 of the finest level's faces).
      flipped += (b - a).cross(c - a).dot(centroid) < -1e-8;
    }
    EXPECT_LE(flipped * 1000, int(l.count / 3)) << "level of error " << l.error;
    end = l.first + l.count;
    previous = l.count;
    previous_error = l.error;
  }
  EXPECT_EQ(indices.size(), size_t(end));
  EXPECT_LT(levels.back().count, sphere.indices.size() / 8);
}

TEST(ShadowLevels, SmallMeshesHaveNone) {
  const MeshData sphere = makeUvSphere(1.0f, 32, 16);
  std::vector<uint32_t> indices = sphere.indices;
  EXPECT_TRUE(shadowLevels(sphere, indices).empty());
  EXPECT_EQ(indices, sphere.indices);
}

TEST(ShadowLevels, TheTexelPicksTheCoarsestLevelWithinIt) {
  GpuMesh g;
  g.index_count = 3000;
  g.shadow_levels = {{0.001f, 3000, 900}, {0.002f, 3900, 300}, {0.004f, 4200, 90}};
  // The model doubles the mesh: a texel of t m allows t / 2 in the mesh's units.
  const Eigen::Matrix4f model = (Eigen::Matrix4f() << 0, -2, 0, 1, 2, 0, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1).finished();
  using Range = std::pair<size_t, GLsizei>;
  EXPECT_EQ(shadowRange(g, model, 0.0019), (Range{0, 3000}));  // finer than every level: the mesh
  EXPECT_EQ(shadowRange(g, model, 0.0021), (Range{3000, 900}));
  EXPECT_EQ(shadowRange(g, model, 0.007), (Range{3900, 300}));
  EXPECT_EQ(shadowRange(g, model, 1.0), (Range{4200, 90}));
  g.shadow_levels.clear();
  EXPECT_EQ(shadowRange(g, model, 1.0), (Range{0, 3000}));
}

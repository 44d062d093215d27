// Meshes into GPU buffers (Renderer::upload, release): a vertex array per mesh, with the file's
// materials (vertex colours, texture coordinates, textures) when it has colours.

#include <meshoptimizer.h>

#include "engine/renderer_impl.h"

namespace ponyhop {

namespace {

// A mesh without colours: position, normal (6 floats a vertex).
void uploadPlain(const MeshData& m, GpuMesh& g) {
  std::vector<float> v;
  v.reserve(m.positions.size() * 6);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Eigen::Vector3f n = i < m.normals.size() ? m.normals[i] : Eigen::Vector3f(0, 0, 1);
    v.insert(v.end(), {m.positions[i].x(), m.positions[i].y(), m.positions[i].z(), n.x(), n.y(), n.z()});
  }
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(3 * sizeof(float)));
}

// A mesh with colours or a hair region: position, normal, colour, uv (12 floats a vertex), and its
// textures. With a hair region the colour's alpha (which nothing else reads) is the hair weight.
void uploadWithMaterials(const MeshData& m, GpuMesh& g) {
  std::vector<float> v;
  v.reserve(m.positions.size() * 12);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Eigen::Vector3f n = i < m.normals.size() ? m.normals[i] : Eigen::Vector3f(0, 0, 1);
    Eigen::Vector4f c = i < m.colors.size() ? m.colors[i] : Eigen::Vector4f(1, 1, 1, 1);
    if (i < m.hair.size()) c.w() = m.hair[i];
    const Eigen::Vector2f t = i < m.uvs.size() ? m.uvs[i] : Eigen::Vector2f(0, 0);
    v.insert(v.end(), {m.positions[i].x(), m.positions[i].y(), m.positions[i].z(), n.x(), n.y(), n.z(), c.x(), c.y(),
                       c.z(), c.w(), t.x(), t.y()});
  }
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
  const GLsizei stride = 12 * sizeof(float);
  const int sizes[4] = {3, 3, 4, 2}, offsets[4] = {0, 3, 6, 10};
  for (GLuint a = 0; a < 4; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<const void*>(size_t(offsets[a]) * sizeof(float)));
  }
  g.materials = true;
  g.hair = !m.hair.empty();
  g.parts = m.parts.empty() ? std::vector<MeshPart>{MeshPart{0, uint32_t(m.indices.size()), -1}} : m.parts;
  for (const MeshTexture& img : m.textures) {
    GLuint tex = 0;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, img.width, img.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 img.rgba.data());
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    g.textures.push_back(tex);
  }
  glBindTexture(GL_TEXTURE_2D, 0);
}

// The triangles of a mesh with a hair region and no colours of its own, all skin first, then those
// with both (the hairline), then all hair (GpuMesh::skin_count, parts, hair_only). The order of a
// closed mesh's triangles changes no pixel: the depth test decides.
std::vector<uint32_t> sortByHair(const MeshData& m, GpuMesh& g) {
  std::vector<uint32_t> groups[3];  // skin, both, hair
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    int skin = 0, hair = 0;
    for (size_t k = 0; k < 3; ++k) {
      const float w = m.hair[m.indices[t + k]];
      skin += w <= 0.0f;
      hair += w >= 1.0f;
    }
    std::vector<uint32_t>& to = groups[skin == 3 ? 0 : (hair == 3 ? 2 : 1)];
    to.insert(to.end(), m.indices.begin() + long(t), m.indices.begin() + long(t + 3));
  }
  g.skin_count = GLsizei(groups[0].size());
  g.parts = {MeshPart{uint32_t(groups[0].size()), uint32_t(groups[1].size()), -1}};
  g.hair_only = MeshPart{uint32_t(groups[0].size() + groups[1].size()), uint32_t(groups[2].size()), -1};
  std::vector<uint32_t> sorted = std::move(groups[0]);
  sorted.insert(sorted.end(), groups[1].begin(), groups[1].end());
  sorted.insert(sorted.end(), groups[2].begin(), groups[2].end());
  return sorted;
}

// Fewest triangles for which a mesh gets shadow levels: below it the shadow pass's cost per
// triangle is not worth the load time.
constexpr size_t kShadowLevelMinTriangles = 8192;
// The levels' error bounds, as fractions of the mesh's extent (meshopt_simplifyScale), finest
// first: doubling, so that a frame's texel finds one within a factor of two of what it allows.
constexpr float kShadowLevelErrors[] = {1.0f / 2048, 1.0f / 1024, 1.0f / 512, 1.0f / 256, 1.0f / 128};

// A convex surface: every face's plane has all the vertices on one side of it (within 1e-5
// of the extent). Only small meshes are tested (a box, a block of terrain);
// larger ones count as not convex.
bool convexSurface(const MeshData& m) {
  const size_t triangles = m.triangleCount();
  if (triangles == 0 || triangles > 512 || m.positions.empty()) return false;
  Eigen::AlignedBox3f box;
  for (const Eigen::Vector3f& p : m.positions) box.extend(p);
  const float tol = 1e-5f * std::max(box.diagonal().norm(), 1e-30f);
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const Eigen::Vector3f& a = m.positions[m.indices[t]];
    Eigen::Vector3f n = (m.positions[m.indices[t + 1]] - a).cross(m.positions[m.indices[t + 2]] - a);
    if (!(n.norm() > tol * tol)) continue;  // a sliver: no plane
    n.normalize();
    bool above = false, below = false;
    for (const Eigen::Vector3f& p : m.positions) {
      const float d = n.dot(p - a);
      above = above || d > tol;
      below = below || d < -tol;
    }
    if (above && below) return false;
  }
  return true;
}

}  // namespace

// The shadow pass draws a large mesh once more than the main pass (44,544 triangles for the
// default head: most of a head scene's shadow pass on llvmpipe, which sets up every triangle on
// the calling thread). A depth map drawn from a surface within a fraction of a texel of the real
// one is the same map, and the main pass keeps every triangle, so the sculpted detail that
// shading shows stays (docs/RENDERING.md, Shadows). Each level is meshoptimizer's edge collapse
// (quadric error, positions only) of the level before it, to what is left of its bound: its
// distance to the mesh is at most the previous level's plus its own to that level (stored,
// reached rather than asked), and a cascade costs a fraction of simplifying the whole mesh each
// time. The indices, into the same vertices, are appended to `indices`. A level that saves
// under a quarter of the previous one's triangles is not kept.
std::vector<GpuMesh::ShadowLevel> shadowLevels(const MeshData& m, std::vector<uint32_t>& indices) {
  std::vector<GpuMesh::ShadowLevel> levels;
  if (m.triangleCount() < kShadowLevelMinTriangles || m.positions.empty()) return levels;
  const float* xyz = m.positions.front().data();
  const size_t stride = sizeof(Eigen::Vector3f);
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  const float scale = meshopt_simplifyScale(xyz, m.positions.size(), stride);
  std::vector<uint32_t> from = m.indices, out(m.indices.size());
  float error = 0.0f;  // of `from`, relative to scale
  for (float bound : kShadowLevelErrors) {
    float reached = 0.0f;
    const size_t n = meshopt_simplify(out.data(), from.data(), from.size(), xyz, m.positions.size(), stride, 0,
                                      bound - error, 0, &reached);
    if (n == 0 || 4 * n > 3 * from.size()) continue;
    error += reached;
    levels.push_back({error * scale, uint32_t(indices.size()), uint32_t(n)});
    indices.insert(indices.end(), out.begin(), out.begin() + long(n));
    from.assign(out.begin(), out.begin() + long(n));
  }
  return levels;
}

MeshHandle Renderer::upload(const MeshData& m) {
  Impl& I = *impl_;
  GpuMesh g;
  g.closed = closedOrientation(m);
  if (!m.colors.empty() || !m.hair.empty())
    uploadWithMaterials(m, g);
  else
    uploadPlain(m, g);
  std::vector<uint32_t> indices = g.hair && m.colors.empty() ? sortByHair(m, g) : m.indices;
  g.shadow_levels = shadowLevels(m, indices);
  glGenBuffers(1, &g.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(uint32_t)), indices.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  g.index_count = GLsizei(m.indices.size());
  for (const auto& p : m.positions) g.bbox.extend(p.cast<double>());
  g.convex = g.closed != 0 && !g.materials && !g.hair && convexSurface(m);
  I.meshes.push_back(g);
  return MeshHandle{int(I.meshes.size()) - 1};
}

void Renderer::release(MeshHandle h) {
  Impl& I = *impl_;
  if (h.id < 0 || h.id >= int(I.meshes.size()) || I.meshes[size_t(h.id)].vao == 0) return;
  GpuMesh& g = I.meshes[size_t(h.id)];
  glDeleteVertexArrays(1, &g.vao);
  glDeleteBuffers(1, &g.vbo);
  glDeleteBuffers(1, &g.ebo);
  if (!g.textures.empty()) glDeleteTextures(GLsizei(g.textures.size()), g.textures.data());
  g = GpuMesh{};
}

}  // namespace ponyhop

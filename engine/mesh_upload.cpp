// Meshes into GPU buffers (Renderer::upload, release): a vertex array per mesh, with the file's
// materials (vertex colours, texture coordinates, textures) when it has colours.

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

// A mesh with colours: position, normal, colour, uv (12 floats a vertex), and its textures.
void uploadWithMaterials(const MeshData& m, GpuMesh& g) {
  std::vector<float> v;
  v.reserve(m.positions.size() * 12);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Eigen::Vector3f n = i < m.normals.size() ? m.normals[i] : Eigen::Vector3f(0, 0, 1);
    const Eigen::Vector4f c = i < m.colors.size() ? m.colors[i] : Eigen::Vector4f(1, 1, 1, 1);
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

}  // namespace

MeshHandle Renderer::upload(const MeshData& m) {
  Impl& I = *impl_;
  GpuMesh g;
  g.closed = closedOrientation(m);
  if (!m.colors.empty())
    uploadWithMaterials(m, g);
  else
    uploadPlain(m, g);
  glGenBuffers(1, &g.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(m.indices.size() * sizeof(uint32_t)), m.indices.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  g.index_count = GLsizei(m.indices.size());
  for (const auto& p : m.positions) g.bbox.extend(p.cast<double>());
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

#include "engine/mesh.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <numbers>

#include "engine/isolated.h"

namespace ponyhop {

static std::string lowerExtension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string e = path.substr(dot + 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

namespace {

// assimp itself, in whatever process calls it.
bool importMesh(const std::string& path, MeshData& out, std::string* err) {
  Assimp::Importer importer;
  unsigned flags = aiProcess_Triangulate | aiProcess_GenSmoothNormals | aiProcess_JoinIdenticalVertices |
                   aiProcess_PreTransformVertices | aiProcess_SortByPType |
                   aiProcess_ValidateDataStructure;
  // No aiProcess_FindDegenerates: marching-cubes meshes hold many zero-area triangles whose
  // removal leaves T-junctions, i.e. pinholes in the rendered surface. Zero-area triangles cost
  // nothing; bad normals are caught below.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  if (lowerExtension(path) == "stl") {
    // STL stores one normal per facet: drop them so that smooth ones are generated.
    flags |= aiProcess_RemoveComponent;
    importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS);
  }
  const aiScene* scene = importer.ReadFile(path, flags);
  if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    if (err) *err = path + ": " + importer.GetErrorString();
    return false;
  }
  MeshData m;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const uint32_t base = uint32_t(m.positions.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      m.positions.emplace_back(p.x, p.y, p.z);
      Eigen::Vector3f n(0, 0, 1);
      if (am->mNormals) {
        const aiVector3D& an = am->mNormals[v];
        n = Eigen::Vector3f(an.x, an.y, an.z);
        const float len = n.norm();
        n = (std::isfinite(len) && len > 1e-12f) ? Eigen::Vector3f(n / len) : Eigen::Vector3f(0, 0, 1);
      }
      m.normals.push_back(n);
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) m.indices.push_back(base + face.mIndices[k]);
    }
  }
  if (m.indices.empty()) {
    if (err) *err = path + ": no triangles in the file";
    return false;
  }
  out = std::move(m);
  return true;
}

// MeshData through the pipe from the import process: three counts, then the arrays.
template <class T>
void putArray(std::string& s, const std::vector<T>& v) {
  const uint64_t n = v.size();
  s.append(reinterpret_cast<const char*>(&n), sizeof(n));
  s.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}
template <class T>
bool getArray(const std::string& s, size_t& at, std::vector<T>& v) {
  uint64_t n = 0;
  if (s.size() - at < sizeof(n)) return false;
  std::memcpy(&n, s.data() + at, sizeof(n));
  at += sizeof(n);
  if (n > (s.size() - at) / sizeof(T)) return false;
  v.resize(size_t(n));
  std::memcpy(static_cast<void*>(v.data()), s.data() + at, size_t(n) * sizeof(T));
  at += size_t(n) * sizeof(T);
  return true;
}

}  // namespace

bool loadMesh(const std::string& path, MeshData& out, std::string* err) {
  // assimp runs in a child process with a time and memory limit (engine/isolated.h): corrupted
  // files crash, abort or hang it (docs/RELIABILITY.md), and they must not take ponyhop along.
  std::string bytes, e;
  const bool ok = runIsolated(
      [&path](std::string& result, std::string& error) {
        MeshData m;
        if (!importMesh(path, m, &error)) return false;
        putArray(result, m.positions);
        putArray(result, m.normals);
        putArray(result, m.indices);
        return true;
      },
      importLimits(), &bytes, &e);
  if (!ok) {
    if (err) *err = e.rfind(path, 0) == 0 ? e : path + ": the importer (assimp) " + e;
    return false;
  }
  // What comes back is checked like any input: sizes agree, indices in range, values finite.
  MeshData m;
  size_t at = 0;
  if (!getArray(bytes, at, m.positions) || !getArray(bytes, at, m.normals) || !getArray(bytes, at, m.indices) ||
      at != bytes.size() || m.normals.size() != m.positions.size() || m.indices.size() % 3 != 0) {
    if (err) *err = path + ": the import process returned inconsistent data";
    return false;
  }
  for (const auto& p : m.positions) {
    if (!p.allFinite()) {
      if (err) *err = path + ": a vertex position is not a finite number";
      return false;
    }
  }
  for (const uint32_t i : m.indices) {
    if (i >= m.positions.size()) {
      if (err) *err = path + ": a triangle refers to vertex " + std::to_string(i) + " of " +
                      std::to_string(m.positions.size());
      return false;
    }
  }
  m.computeBounds();
  out = std::move(m);
  return true;
}

Eigen::Affine3d meshToBody(const HeadParams& head, const Eigen::AlignedBox3f& bbox) {
  Eigen::Matrix3d U = Eigen::Matrix3d::Identity();
  int up = 2;
  if (head.up_axis == UpAxis::Y) {
    U = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
    up = 1;
  }
  double s = head.scale;
  if (head.height > 0.0 && !bbox.isEmpty()) {
    const double extent = double(bbox.max()[up] - bbox.min()[up]);
    if (extent > 0.0) s = head.height / extent;
  }
  const double k = std::numbers::pi / 180.0;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(head.rotation.z() * k, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(head.rotation.y() * k, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(head.rotation.x() * k, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  Eigen::Affine3d T = Eigen::Affine3d::Identity();
  T.linear() = R * (s * U);
  T.translation() = head.offset;
  return T;
}

Eigen::Vector3d meshPointToBody(const HeadParams& head, const Eigen::AlignedBox3f& bbox, const Eigen::Vector3d& p) {
  return meshToBody(head, bbox) * p;
}

void transformMesh(MeshData& mesh, const Eigen::Affine3d& T) {
  const Eigen::Affine3f Tf = T.cast<float>();
  const Eigen::Matrix3f N = Tf.linear().inverse().transpose();
  for (auto& p : mesh.positions) p = Tf * p;
  for (auto& n : mesh.normals) {
    n = N * n;
    const float len = n.norm();
    if (len > 1e-20f) n /= len;
  }
  if (Tf.linear().determinant() < 0.0f)  // a mirror flips the winding
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) std::swap(mesh.indices[i + 1], mesh.indices[i + 2]);
  mesh.computeBounds();
}

MeshData makeUvSphere(float radius, int slices, int stacks) {
  MeshData m;
  slices = std::max(slices, 3);
  stacks = std::max(stacks, 2);
  const float pi = std::numbers::pi_v<float>;
  for (int i = 0; i <= stacks; ++i) {
    const float phi = pi * float(i) / float(stacks);  // from +z down
    for (int j = 0; j <= slices; ++j) {
      const float th = 2.0f * pi * float(j) / float(slices);
      const Eigen::Vector3f n(std::sin(phi) * std::cos(th), std::sin(phi) * std::sin(th), std::cos(phi));
      m.positions.push_back(radius * n);
      m.normals.push_back(n);
    }
  }
  const int row = slices + 1;
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const uint32_t a = uint32_t(i * row + j), b = a + 1, c = a + uint32_t(row), d = c + 1;
      if (i != 0) m.indices.insert(m.indices.end(), {a, c, b});
      if (i != stacks - 1) m.indices.insert(m.indices.end(), {b, c, d});
    }
  m.computeBounds();
  return m;
}

MeshData makeBoxMesh(const Eigen::Vector3f& h) {
  MeshData m;
  for (int axis = 0; axis < 3; ++axis)
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = float(sgn);
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      const uint32_t base = uint32_t(m.positions.size());
      for (int k = 0; k < 4; ++k) {
        Eigen::Vector3f p;
        p[axis] = float(sgn) * h[axis];
        p[a1] = ((k == 1 || k == 2) ? 1.0f : -1.0f) * h[a1];
        p[a2] = (k >= 2 ? 1.0f : -1.0f) * h[a2];
        m.positions.push_back(p);
        m.normals.push_back(n);
      }
      // Counter-clockwise seen from outside: (a1, a2, n) is right-handed, so flip for sgn < 0.
      if (sgn > 0)
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      else
        m.indices.insert(m.indices.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
    }
  m.computeBounds();
  return m;
}

}  // namespace ponyhop

#include "engine/mesh.h"

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <stb_image.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numbers>
#include <unordered_map>

#include "engine/isolated.h"
#include "sim/head_fit.h"

namespace ponyhop {

static std::string lowerExtension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string e = path.substr(dot + 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

namespace {

// assimp's MD2 importer names this placeholder when the file names no skin (its source says
// "TODO: guess the name of the texture file from the model file name"): not a file anyone named.
constexpr const char* kAssimpDummyTexture = "$texture_dummy.bmp";

// The skin of a model that names none: as Quake II keeps them, an image beside the model under
// its name (sydney.md2, sydney.bmp), else the first (by name) that extends its name
// (faerie.md2, faerie2.bmp). Empty when there is none.
std::string skinBesideModel(const std::string& mesh_path) {
  namespace fs = std::filesystem;
  const fs::path mesh(mesh_path);
  const std::string stem = mesh.stem().string();
  std::error_code ec;
  std::string exact, extended;
  for (const fs::directory_entry& e :
       fs::directory_iterator(mesh.parent_path().empty() ? "." : mesh.parent_path(), ec)) {
    const std::string ext = lowerExtension(e.path().string());
    if (ext != "bmp" && ext != "png" && ext != "jpg" && ext != "jpeg" && ext != "tga") continue;
    const std::string name = e.path().stem().string();
    if (name == stem) exact = e.path().string();
    if (name.size() > stem.size() && name.compare(0, stem.size(), stem) == 0 &&
        (extended.empty() || e.path().string() < extended)) {
      extended = e.path().string();
    }
  }
  return exact.empty() ? extended : exact;
}

// The base-colour texture of a material: an image embedded in the file ("*N" or by name), or a
// file beside the mesh. Empty image + a warning (one plain sentence) when it cannot be read.
MeshTexture readTexture(const aiScene* scene, const aiString& ref, const std::string& mesh_path, std::string* warning) {
  MeshTexture img;
  const aiTexture* emb = scene->GetEmbeddedTexture(ref.C_Str());
  int w = 0, h = 0, n = 0;
  unsigned char* data = nullptr;
  const std::string mesh_name = std::filesystem::path(mesh_path).filename().string();
  std::string what = ref.C_Str();
  if (emb) {
    what = "the texture " + what + " embedded in " + mesh_name;
    if (emb->mHeight == 0) {  // compressed (png, jpg...): mWidth bytes
      data = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(emb->pcData), int(emb->mWidth), &w, &h, &n, 4);
    } else {  // raw texels, BGRA
      img.width = int(emb->mWidth);
      img.height = int(emb->mHeight);
      img.rgba.resize(size_t(img.width) * size_t(img.height) * 4);
      for (size_t i = 0; i < size_t(emb->mWidth) * emb->mHeight; ++i) {
        const aiTexel& t = emb->pcData[i];
        img.rgba[4 * i] = t.r, img.rgba[4 * i + 1] = t.g, img.rgba[4 * i + 2] = t.b, img.rgba[4 * i + 3] = t.a;
      }
      return img;
    }
  } else if (what == kAssimpDummyTexture) {
    what = skinBesideModel(mesh_path);
    if (what.empty()) return img;  // the file names no texture and none lies beside it: nothing to say
    data = stbi_load(what.c_str(), &w, &h, &n, 4);
    what = "the skin " + what;
  } else {
    std::string rel = what;
    for (char& c : rel)
      if (c == '\\') c = '/';
    const std::filesystem::path p = std::filesystem::path(mesh_path).parent_path() / rel;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec)) {
      *warning = "the texture " + what + " that " + mesh_name + " names is not there (no file " + p.string() +
                 "): drawn without it";
      return img;
    }
    what = "the texture " + p.string();
    data = stbi_load(p.string().c_str(), &w, &h, &n, 4);
  }
  if (!data) {
    *warning = what + " is not an image ponyhop reads (" + (stbi_failure_reason() ? stbi_failure_reason() : "?") +
               "): drawn without it";
    return img;
  }
  img.width = w;
  img.height = h;
  img.rgba.assign(data, data + size_t(w) * size_t(h) * 4);
  stbi_image_free(data);
  return img;
}

// The up axis the file states (MeshData::file_up). An importer that converts a z-up format to
// assimp's y up puts the rotation on the root node: the root's y row then reads the file's z.
char statedUpAxis(const aiScene& scene) {
  const aiMatrix4x4& r = scene.mRootNode->mTransformation;
  const double row_y = std::sqrt(double(r.b1) * r.b1 + double(r.b2) * r.b2 + double(r.b3) * r.b3);
  if (row_y > 0.0 && std::abs(double(r.b3)) > 0.99 * row_y) return 'y';
  int32_t up = -1;
  if (scene.mMetaData && scene.mMetaData->Get("UpAxis", up)) {  // FBX: 1 y, 2 z
    if (up == 1) return 'y';
    if (up == 2) return 'z';
  }
  return 0;
}

// A skinned mesh is drawn in its skeleton's rest pose: each vertex where its bones put it (the sum
// over its bones of weight x bone node's global transform x offset matrix), as a viewer shows the
// file with no animation playing. PreTransformVertices, which follows, places a mesh by its own
// node's transform alone; for most files the two agree (the skeleton rests in the bind pose) and
// the mesh is left untouched, bit for bit. Where they differ (DirectX's BCN_Epileptic.X: the head,
// torso and legs each come out displaced and turned, head down), the rest pose is written back in
// the mesh node's frame, so that PreTransformVertices puts it where the bones do.
void poseSkinnedMeshes(aiScene& scene) {
  std::vector<const aiNode*> node_of(scene.mNumMeshes, nullptr);
  std::vector<const aiNode*> stack{scene.mRootNode};
  while (!stack.empty()) {
    const aiNode* n = stack.back();
    stack.pop_back();
    for (unsigned i = 0; i < n->mNumMeshes; ++i)
      if (n->mMeshes[i] < scene.mNumMeshes && !node_of[n->mMeshes[i]]) node_of[n->mMeshes[i]] = n;
    for (unsigned c = 0; c < n->mNumChildren; ++c) stack.push_back(n->mChildren[c]);
  }
  const auto global = [](const aiNode* n) {
    aiMatrix4x4 g;
    for (; n; n = n->mParent) g = n->mTransformation * g;
    return g;
  };
  for (unsigned mi = 0; mi < scene.mNumMeshes; ++mi) {
    aiMesh* am = scene.mMeshes[mi];
    if (am->mNumBones == 0 || !node_of[mi] || am->mNumVertices == 0) continue;
    const aiMatrix4x4 node = global(node_of[mi]);
    std::vector<aiVector3D> pos(am->mNumVertices, aiVector3D(0, 0, 0)), nor(am->mNumVertices, aiVector3D(0, 0, 0));
    std::vector<float> weight(am->mNumVertices, 0.0f);
    bool usable = true;
    for (unsigned b = 0; b < am->mNumBones && usable; ++b) {
      const aiBone* bone = am->mBones[b];
      const aiNode* bn = scene.mRootNode->FindNode(bone->mName);
      if (!bn) {
        usable = false;  // a bone with no node: the file's own placement is all there is
        break;
      }
      const aiMatrix4x4 M = global(bn) * bone->mOffsetMatrix;
      const aiMatrix3x3 R(M);
      for (unsigned k = 0; k < bone->mNumWeights; ++k) {
        const aiVertexWeight& w = bone->mWeights[k];
        if (w.mVertexId >= am->mNumVertices || !(w.mWeight > 0.0f)) continue;
        pos[w.mVertexId] += (M * am->mVertices[w.mVertexId]) * w.mWeight;
        if (am->mNormals) nor[w.mVertexId] += (R * am->mNormals[w.mVertexId]) * w.mWeight;
        weight[w.mVertexId] += w.mWeight;
      }
    }
    if (!usable) continue;
    // Does the rest pose differ from the node's placement? (Beyond float round-off: 1e-4 of the
    // mesh's size.)
    aiVector3D lo(1e30f, 1e30f, 1e30f), hi(-1e30f, -1e30f, -1e30f);
    float moved = 0.0f;
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D placed = node * am->mVertices[v];
      lo = aiVector3D(std::min(lo.x, placed.x), std::min(lo.y, placed.y), std::min(lo.z, placed.z));
      hi = aiVector3D(std::max(hi.x, placed.x), std::max(hi.y, placed.y), std::max(hi.z, placed.z));
      if (weight[v] > 0.0f) moved = std::max(moved, (pos[v] / weight[v] - placed).Length());
    }
    if (!(moved > 1e-4f * (hi - lo).Length())) continue;
    aiMatrix4x4 to_node = node;
    to_node.Inverse();
    const aiMatrix3x3 to_node_r(to_node);
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      if (!(weight[v] > 0.0f)) continue;  // no bone holds it: where its node puts it
      am->mVertices[v] = to_node * (pos[v] / weight[v]);
      if (am->mNormals) am->mNormals[v] = (to_node_r * nor[v]).NormalizeSafe();
    }
  }
}

// assimp itself, in whatever process calls it.
bool importMesh(const std::string& path, MeshData& out, std::string* err) {
  Assimp::Importer importer;
  unsigned flags = aiProcess_Triangulate | aiProcess_GenSmoothNormals | aiProcess_JoinIdenticalVertices |
                   aiProcess_PreTransformVertices | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
  // No aiProcess_FindDegenerates: marching-cubes meshes hold many zero-area triangles whose
  // removal leaves T-junctions, i.e. pinholes in the rendered surface. Zero-area triangles cost
  // nothing; bad normals are caught below.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  if (lowerExtension(path) == "stl") {
    // STL stores one normal per facet: drop them so that smooth ones are generated.
    flags |= aiProcess_RemoveComponent;
    importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_NORMALS);
  }
  // Read first, post-process after: the root node's own transform (which PreTransformVertices
  // bakes in and resets) tells whether the importer turned the file's axes.
  const aiScene* scene = importer.ReadFile(path, 0);
  char file_up = 0;
  if (scene && scene->mRootNode) {
    file_up = statedUpAxis(*scene);
    // The importer's own scene, changed in place before its post-processing (the Importer owns it
    // and hands it out const only to keep callers from changing it behind the post-processing).
    poseSkinnedMeshes(const_cast<aiScene&>(*scene));
  }
  if (scene) scene = importer.ApplyPostProcessing(flags);
  if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    // An incomplete scene comes with no error string (Half-Life's manT.mdl holds textures only).
    const std::string why = importer.GetErrorString();
    if (err) *err = path + ": " + (why.empty() ? "assimp read no mesh from it (an incomplete scene)" : why);
    return false;
  }
  MeshData m;
  m.file_up = file_up;
  std::map<std::string, int> texture_of;  // by reference, -1: unreadable
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const uint32_t base = uint32_t(m.positions.size());
    // Material: base colour (glTF) or diffuse colour, and a base-colour (or diffuse) texture.
    Eigen::Vector4f factor(1, 1, 1, 1);
    int texture = -1;
    bool hair_region = false;
    if (am->mMaterialIndex < scene->mNumMaterials) {
      const aiMaterial* mat = scene->mMaterials[am->mMaterialIndex];
      // The hair region of ponyhop's own head (assets/head/README.md): the vertex colours' alpha
      // is 1 - hair weight, their rgb only what other viewers show.
      hair_region = am->mColors[0] && std::strcmp(mat->GetName().C_Str(), kHairRegionMaterial) == 0;
      if (hair_region && m.hair.empty()) m.hair.assign(m.positions.size(), 0.0f);
      aiColor4D c;
      if (mat->Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS || mat->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) {
        factor = Eigen::Vector4f(c.r, c.g, c.b, c.a);
      }
      aiString ref;
      if ((mat->GetTexture(aiTextureType_BASE_COLOR, 0, &ref) == AI_SUCCESS ||
           mat->GetTexture(aiTextureType_DIFFUSE, 0, &ref) == AI_SUCCESS) &&
          am->mTextureCoords[0]) {
        auto it = texture_of.find(ref.C_Str());
        if (it == texture_of.end()) {
          std::string warning;
          MeshTexture img = readTexture(scene, ref, path, &warning);
          int id = -1;
          if (img.width > 0) {
            id = int(m.textures.size());
            m.textures.push_back(std::move(img));
          } else if (!warning.empty()) {
            m.warnings.push_back(warning);
          }
          it = texture_of.emplace(ref.C_Str(), id).first;
        }
        texture = it->second;
      }
    }
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
      Eigen::Vector4f color = factor;
      if (hair_region) {
        m.hair.push_back(std::clamp(1.0f - am->mColors[0][v].a, 0.0f, 1.0f));
      } else if (am->mColors[0]) {
        const aiColor4D& vc = am->mColors[0][v];
        color = color.cwiseProduct(Eigen::Vector4f(vc.r, vc.g, vc.b, vc.a));
      }
      if (!hair_region && !m.hair.empty()) m.hair.push_back(0.0f);
      m.colors.push_back(color);
      const aiVector3D uv = am->mTextureCoords[0] ? am->mTextureCoords[0][v] : aiVector3D(0, 0, 0);
      m.uvs.emplace_back(uv.x, 1.0f - uv.y);  // assimp: v up from the bottom; images: top row first
    }
    const uint32_t first = uint32_t(m.indices.size());
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) m.indices.push_back(base + face.mIndices[k]);
    }
    const uint32_t count = uint32_t(m.indices.size()) - first;
    if (!m.parts.empty() && m.parts.back().texture == texture && m.parts.back().first + m.parts.back().count == first) {
      m.parts.back().count += count;
    } else {
      m.parts.push_back(MeshPart{first, count, texture});
    }
  }
  if (m.indices.empty()) {
    if (err) *err = path + ": no triangles in the file";
    return false;
  }
  // One plain colour says nothing a scene's own colour does not: kept only when they vary.
  if (!m.hasOwnColors()) m.dropMaterials();
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
  // An empty vector's data() may be null, and memcpy's arguments must never be (UBSan).
  if (n > 0) std::memcpy(static_cast<void*>(v.data()), s.data() + at, size_t(n) * sizeof(T));
  at += size_t(n) * sizeof(T);
  return true;
}

// The materials after the geometry: colours, uvs, parts, texture sizes and texels, warnings.
void putMaterials(std::string& s, const MeshData& m) {
  putArray(s, m.colors);
  putArray(s, m.hair);
  putArray(s, m.uvs);
  putArray(s, m.parts);
  std::vector<int32_t> dims;
  std::vector<uint8_t> texels;
  for (const MeshTexture& t : m.textures) {
    dims.insert(dims.end(), {t.width, t.height});
    texels.insert(texels.end(), t.rgba.begin(), t.rgba.end());
  }
  putArray(s, dims);
  putArray(s, texels);
  std::vector<char> text;
  for (const std::string& w : m.warnings) {
    text.insert(text.end(), w.begin(), w.end());
    text.push_back('\n');
  }
  putArray(s, text);
}

bool getMaterials(const std::string& s, size_t& at, MeshData& m) {
  std::vector<int32_t> dims;
  std::vector<uint8_t> texels;
  std::vector<char> text;
  if (!getArray(s, at, m.colors) || !getArray(s, at, m.hair) || !getArray(s, at, m.uvs) || !getArray(s, at, m.parts) ||
      !getArray(s, at, dims) || !getArray(s, at, texels) || !getArray(s, at, text) || dims.size() % 2 != 0) {
    return false;
  }
  if ((!m.colors.empty() && m.colors.size() != m.positions.size()) ||
      (!m.hair.empty() && m.hair.size() != m.positions.size()) ||
      (!m.uvs.empty() && m.uvs.size() != m.positions.size())) {
    return false;
  }
  size_t used = 0;
  for (size_t i = 0; i < dims.size(); i += 2) {
    if (dims[i] <= 0 || dims[i + 1] <= 0 || dims[i] > 16384 || dims[i + 1] > 16384) return false;
    const size_t n = size_t(dims[i]) * size_t(dims[i + 1]) * 4;
    if (texels.size() - used < n) return false;
    m.textures.push_back(MeshTexture{
        dims[i], dims[i + 1], std::vector<uint8_t>(texels.begin() + long(used), texels.begin() + long(used + n))});
    used += n;
  }
  if (used != texels.size()) return false;
  for (const MeshPart& p : m.parts) {
    if (p.texture >= int32_t(m.textures.size()) || uint64_t(p.first) + p.count > m.indices.size()) return false;
  }
  std::string w;
  for (char c : text) {
    if (c == '\n') {
      m.warnings.push_back(w);
      w.clear();
    } else {
      w += c;
    }
  }
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
        putMaterials(result, m);
        putArray(result, std::vector<char>{m.file_up});
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
  std::vector<char> file_up;
  if (!getArray(bytes, at, m.positions) || !getArray(bytes, at, m.normals) || !getArray(bytes, at, m.indices) ||
      !getMaterials(bytes, at, m) || !getArray(bytes, at, file_up) || at != bytes.size() ||
      m.normals.size() != m.positions.size() || m.indices.size() % 3 != 0 || file_up.size() != 1 ||
      (file_up[0] != 0 && file_up[0] != 'y' && file_up[0] != 'z')) {
    if (err) *err = path + ": the import process returned inconsistent data";
    return false;
  }
  m.file_up = file_up[0];
  for (const auto& p : m.positions) {
    if (!p.allFinite()) {
      if (err) *err = path + ": a vertex position is not a finite number";
      return false;
    }
  }
  for (const uint32_t i : m.indices) {
    if (i >= m.positions.size()) {
      if (err)
        *err =
            path + ": a triangle refers to vertex " + std::to_string(i) + " of " + std::to_string(m.positions.size());
      return false;
    }
  }
  m.computeBounds();
  out = std::move(m);
  return true;
}

Eigen::Affine3d meshToBody(const HeadParams& head, const Eigen::AlignedBox3f& bbox) {
  HeadFit fit;
  fit.up = head.up_axis == UpAxis::Z ? UpAxis::Z : UpAxis::Y;
  fit.head_bounds = bbox;
  return headMeshToBody(head, fit);
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

MeshData makeCapsuleMesh(const Eigen::Vector3f& p0, float r0, const Eigen::Vector3f& p1, float r1, int slices,
                         int stacks) {
  MeshData m = makeUvSphere(1.0f, slices, stacks | 1);  // odd: no ring on the equator
  const Eigen::Vector3f axis = p1 - p0;
  const float len = axis.norm();
  const Eigen::Quaternionf R = len > 1e-9f ? Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), axis / len)
                                           : Eigen::Quaternionf::Identity();
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Eigen::Vector3f n = m.positions[i];  // unit sphere: position = normal
    const bool top = n.z() > 0.0f;
    m.positions[i] = (top ? p1 : p0) + R * (n * (top ? r1 : r0));
    m.normals[i] = R * n;
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

int closedOrientation(const MeshData& mesh) {
  const size_t nt = mesh.triangleCount();
  if (nt == 0) return 0;
  Eigen::AlignedBox3d box;
  for (const auto& p : mesh.positions) box.extend(p.cast<double>());
  const Eigen::Vector3d ext = box.sizes();
  // Vertices welded by position on a grid of 1e-6 of the mesh's size: files split a vertex where
  // its normal or uv changes, and a seam's two copies may differ in the last bits. A vertex pair
  // that straddles a cell boundary only makes the mesh look open (drawn from both sides: safe).
  const double cell = std::max(1e-6 * ext.maxCoeff(), 1e-12);
  std::map<std::array<long long, 3>, uint32_t> ids;
  std::vector<uint32_t> weld(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const Eigen::Vector3d q = (mesh.positions[i].cast<double>() - box.min()) / cell;
    const std::array<long long, 3> key{std::llround(q.x()), std::llround(q.y()), std::llround(q.z())};
    weld[i] = ids.emplace(key, uint32_t(ids.size())).first->second;
  }
  // Every directed edge once, and its reverse once: closed and consistently wound.
  std::unordered_map<uint64_t, int> directed;
  directed.reserve(3 * nt);
  double volume = 0.0;
  for (size_t t = 0; t < nt; ++t) {
    uint32_t v[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = mesh.indices[3 * t + size_t(k)];
      if (i >= weld.size()) return 0;
      v[k] = weld[i];
    }
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) continue;  // degenerate: no edge of its own
    for (int k = 0; k < 3; ++k) {
      if (++directed[uint64_t(v[k]) << 32 | v[(k + 1) % 3]] > 1) return 0;
    }
    const Eigen::Vector3d a = mesh.positions[mesh.indices[3 * t]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[mesh.indices[3 * t + 1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[mesh.indices[3 * t + 2]].cast<double>();
    volume += a.dot(b.cross(c)) / 6.0;
  }
  for (const auto& e : directed) {
    if (directed.find((e.first << 32) | (e.first >> 32)) == directed.end()) return 0;
  }
  const double tiny = 1e-9 * ext.x() * ext.y() * ext.z();
  return volume > tiny ? 1 : volume < -tiny ? -1 : 0;
}

}  // namespace ponyhop

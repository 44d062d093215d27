#include "engine/gltf_export.h"

#include <assimp/material.h>
#include <assimp/scene.h>

#include <assimp/Exporter.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace ponyhop {
namespace {

aiMatrix4x4 toAi(const Eigen::Affine3d& T) {
  const Eigen::Matrix4d m = T.matrix();
  return aiMatrix4x4(float(m(0, 0)), float(m(0, 1)), float(m(0, 2)), float(m(0, 3)), float(m(1, 0)), float(m(1, 1)),
                     float(m(1, 2)), float(m(1, 3)), float(m(2, 0)), float(m(2, 1)), float(m(2, 2)), float(m(2, 3)),
                     0.0f, 0.0f, 0.0f, 1.0f);
}

aiMesh* toAiMesh(const BakeMesh& b, unsigned material) {
  auto* m = new aiMesh();
  m->mName = b.name;
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  m->mMaterialIndex = material;
  const MeshData& d = b.mesh;
  m->mNumVertices = unsigned(d.positions.size());
  m->mVertices = new aiVector3D[m->mNumVertices];
  m->mNormals = new aiVector3D[m->mNumVertices];
  for (unsigned i = 0; i < m->mNumVertices; ++i) {
    m->mVertices[i] = aiVector3D(d.positions[i].x(), d.positions[i].y(), d.positions[i].z());
    m->mNormals[i] = aiVector3D(d.normals[i].x(), d.normals[i].y(), d.normals[i].z());
  }
  if (!d.hair.empty()) {
    // The hair region: rgb what another viewer shows (the hair's colour over the base colour),
    // alpha 1 - hair weight (ignored by glTF under alphaMode OPAQUE), read back by loadMesh.
    m->mColors[0] = new aiColor4D[m->mNumVertices];
    const Eigen::Vector3f ratio = b.hair_color.cwiseQuotient(b.color.cwiseMax(1e-3f));
    for (unsigned i = 0; i < m->mNumVertices; ++i) {
      const float w = i < d.hair.size() ? d.hair[i] : 0.0f;
      const Eigen::Vector3f c = Eigen::Vector3f::Ones() + w * (ratio - Eigen::Vector3f::Ones());
      m->mColors[0][i] = aiColor4D(c.x(), c.y(), c.z(), 1.0f - w);
    }
  }
  m->mNumFaces = unsigned(d.indices.size() / 3);
  m->mFaces = new aiFace[m->mNumFaces];
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    m->mFaces[f].mNumIndices = 3;
    m->mFaces[f].mIndices = new unsigned[3]{d.indices[3 * f], d.indices[3 * f + 1], d.indices[3 * f + 2]};
  }
  return m;
}

aiMaterial* toAiMaterial(const BakeMesh& b) {
  auto* mat = new aiMaterial();
  const aiString name(b.mesh.hair.empty() ? b.name : std::string(kHairRegionMaterial));
  mat->AddProperty(&name, AI_MATKEY_NAME);
  const aiColor4D base(b.color.x(), b.color.y(), b.color.z(), 1.0f);
  mat->AddProperty(&base, 1, AI_MATKEY_BASE_COLOR);
  const aiColor3D diffuse(b.color.x(), b.color.y(), b.color.z());
  mat->AddProperty(&diffuse, 1, AI_MATKEY_COLOR_DIFFUSE);
  const float metallic = 0.0f, roughness = 0.6f;
  mat->AddProperty(&metallic, 1, AI_MATKEY_METALLIC_FACTOR);
  mat->AddProperty(&roughness, 1, AI_MATKEY_ROUGHNESS_FACTOR);
  return mat;
}

}  // namespace

bool writeGlb(const Bake& bake, const std::string& path, std::string* err) {
  const auto fail = [&](const std::string& m) {
    if (err) *err = path + ": " + m;
    return false;
  };
  for (const BakeNode& n : bake.nodes) {
    const bool animated = !n.translation.empty() || !n.rotation.empty();
    if (animated && (n.translation.size() != bake.times.size() || n.rotation.size() != bake.times.size())) {
      return fail("node " + n.name + ": one translation and rotation per sample time needed");
    }
  }
  auto scene = std::make_unique<aiScene>();
  scene->mNumMaterials = unsigned(bake.meshes.size());
  scene->mMaterials = new aiMaterial*[std::max<size_t>(1, bake.meshes.size())];
  scene->mNumMeshes = unsigned(bake.meshes.size());
  scene->mMeshes = new aiMesh*[std::max<size_t>(1, bake.meshes.size())];
  for (size_t i = 0; i < bake.meshes.size(); ++i) {
    scene->mMaterials[i] = toAiMaterial(bake.meshes[i]);
    scene->mMeshes[i] = toAiMesh(bake.meshes[i], unsigned(i));
  }
  if (bake.meshes.empty()) {  // the exporter wants a material
    scene->mNumMaterials = 1;
    scene->mMaterials[0] = new aiMaterial();
  }

  // Nodes: built first, children attached after (every parent index is an earlier node).
  auto* root = new aiNode(bake.root_name);
  scene->mRootNode = root;
  Eigen::Affine3d root_T = Eigen::Affine3d::Identity();
  root_T.linear() = bake.root_rotation.toRotationMatrix();
  root->mTransformation = toAi(root_T);
  std::vector<aiNode*> nodes;
  std::vector<std::vector<aiNode*>> children(bake.nodes.size() + 1);  // [0]: the root's
  for (size_t i = 0; i < bake.nodes.size(); ++i) {
    const BakeNode& b = bake.nodes[i];
    auto* n = new aiNode(b.name);
    Eigen::Affine3d T = b.local;
    if (!b.translation.empty()) {
      T = Eigen::Affine3d::Identity();
      T.translate(b.translation.front());
      T.rotate(b.rotation.front());
    }
    n->mTransformation = toAi(T);
    if (b.mesh >= 0) {
      n->mNumMeshes = 1;
      n->mMeshes = new unsigned[1]{unsigned(b.mesh)};
    }
    nodes.push_back(n);
    if (b.parent >= int(i)) return fail("node " + b.name + ": its parent must come before it");
    children[size_t(b.parent + 1)].push_back(n);
  }
  const auto attach = [](aiNode* parent, const std::vector<aiNode*>& kids) {
    if (kids.empty()) return;
    parent->mNumChildren = unsigned(kids.size());
    parent->mChildren = new aiNode*[kids.size()];
    for (size_t k = 0; k < kids.size(); ++k) {
      parent->mChildren[k] = kids[k];
      kids[k]->mParent = parent;
    }
  };
  attach(root, children[0]);
  for (size_t i = 0; i < nodes.size(); ++i) attach(nodes[i], children[i + 1]);

  // One animation, a channel per animated node. Key times in ms (ticks per second 1000, as
  // assimp's own glTF importer gives them).
  std::vector<aiNodeAnim*> channels;
  for (const BakeNode& b : bake.nodes) {
    if (b.translation.empty()) continue;
    auto* c = new aiNodeAnim();
    c->mNodeName = b.name;
    const unsigned k = unsigned(bake.times.size());
    c->mNumPositionKeys = c->mNumRotationKeys = c->mNumScalingKeys = k;
    c->mPositionKeys = new aiVectorKey[k];
    c->mRotationKeys = new aiQuatKey[k];
    c->mScalingKeys = new aiVectorKey[k];
    for (unsigned j = 0; j < k; ++j) {
      const double t = 1000.0 * bake.times[j];
      const Eigen::Vector3d& p = b.translation[j];
      const Eigen::Quaterniond& q = b.rotation[j];
      c->mPositionKeys[j] = aiVectorKey(t, aiVector3D(float(p.x()), float(p.y()), float(p.z())));
      c->mRotationKeys[j] = aiQuatKey(t, aiQuaternion(float(q.w()), float(q.x()), float(q.y()), float(q.z())));
      c->mScalingKeys[j] = aiVectorKey(t, aiVector3D(1.0f, 1.0f, 1.0f));
    }
    channels.push_back(c);
  }
  if (!channels.empty()) {
    auto* a = new aiAnimation();
    a->mName = bake.animation_name;
    a->mTicksPerSecond = 1000.0;
    a->mDuration = 1000.0 * (bake.times.back() - bake.times.front());
    a->mNumChannels = unsigned(channels.size());
    a->mChannels = new aiNodeAnim*[channels.size()];
    for (size_t i = 0; i < channels.size(); ++i) a->mChannels[i] = channels[i];
    scene->mNumAnimations = 1;
    scene->mAnimations = new aiAnimation* [1] { a };
  }

  const std::string tmp = path + ".tmp";
  Assimp::Exporter exporter;
  if (exporter.Export(scene.get(), "glb2", tmp) != aiReturn_SUCCESS) {
    std::remove(tmp.c_str());
    return fail(std::string("assimp's glTF exporter: ") + exporter.GetErrorString());
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    return fail(ec.message());
  }
  return true;
}

}  // namespace ponyhop

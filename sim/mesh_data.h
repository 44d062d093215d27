// A triangle mesh as plain data: what a mesh file becomes after import (engine/mesh.h loads it
// through assimp), what the renderer uploads, and what the simulation may read (the head's
// bounds and triangles). No file format, no GL here.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace ponyhop {

// Materials, when the file has them (all empty otherwise): colours are linear RGBA (a material's
// base colour times the vertex colour, as glTF defines them), textures are sRGB base-colour maps.
struct MeshPart {
  uint32_t first = 0;    // first index
  uint32_t count = 0;    // indices
  int32_t texture = -1;  // into MeshData::textures
};

struct MeshTexture {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;  // top row first
};

// One indexed triangle list; all meshes/nodes of a file are merged with their node transforms
// baked in. normals.size() == positions.size(), unit length.
struct MeshData {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  std::vector<uint32_t> indices;        // 3 per triangle
  Eigen::AlignedBox3f bbox;             // of positions (empty when there are none)
  std::vector<Eigen::Vector4f> colors;  // per vertex, or empty
  std::vector<Eigen::Vector2f> uvs;     // per vertex (v = 0 at the image's top row), or empty
  std::vector<MeshPart> parts;          // index ranges by texture, or empty
  std::vector<MeshTexture> textures;
  // Per vertex, 0 skin .. 1 hair: the hair region a head file marks (the default head's cap,
  // parting and bun: COLOR_0's alpha in a material named "ponyhop_head", assets/head/README.md),
  // drawn as hair; or empty. Kept by dropMaterials() (it is no colour of the file's).
  std::vector<float> hair;
  std::vector<std::string> warnings;  // e.g. a texture that cannot be read
  // The up axis the file itself states, as assimp returns it: 'y' when the importer turned the
  // file's z up into y up (a rotation on its root node: MD2, IQM, 3DS, MDL...) or the file says y
  // (FBX's UpAxis); 'z' when the file says z and was not turned; 0 when the file says nothing
  // (OBJ, PLY, STL, Blender...).
  char file_up = 0;

  size_t triangleCount() const { return indices.size() / 3; }
  // More than one plain colour: vertex colours, several base colours, or a texture.
  bool hasOwnColors() const {
    if (!textures.empty()) return true;
    for (const auto& c : colors)
      if (!c.isApprox(colors.front(), 1e-4f)) return true;
    return false;
  }
  void dropMaterials() {  // colours, uvs, parts and textures
    colors.clear();
    uvs.clear();
    parts.clear();
    textures.clear();
  }
  void computeBounds() {
    bbox.setEmpty();
    for (const auto& p : positions) bbox.extend(p);
  }
};

}  // namespace ponyhop

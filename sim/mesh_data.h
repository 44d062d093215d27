// A triangle mesh as plain data: what a mesh file becomes after import (engine/mesh.h loads it
// through assimp), what the renderer uploads, and what the simulation may read (the head's
// bounds and triangles). No file format, no GL here.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace ponyhop {

// One indexed triangle list; all meshes/nodes of a file are merged with their node transforms
// baked in. normals.size() == positions.size(), unit length.
struct MeshData {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  std::vector<uint32_t> indices;  // 3 per triangle
  Eigen::AlignedBox3f bbox;       // of positions (empty when there are none)

  size_t triangleCount() const { return indices.size() / 3; }
  void computeBounds() {
    bbox.setEmpty();
    for (const auto& p : positions) bbox.extend(p);
  }
};

}  // namespace ponyhop

// A 10 cm cube as a head mesh, for sim tests that need a head collider without the real head's
// grid (a few thousand cells, built in milliseconds).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/assets.h"

namespace ponyhop {

// A 10 cm cube as the head: 8 corners, 12 triangles facing out.
struct CubeHead {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<uint32_t> indices;
  CubeHead() {
    for (int i = 0; i < 8; ++i) vertices.emplace_back(i & 1 ? 0.05 : -0.05, i & 2 ? 0.05 : -0.05, i & 4 ? 0.05 : -0.05);
    indices = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
               2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  }
};

// The cube as the head, anchored at the middle of its -y face.
class CubeAssets : public AssetLoader {
 public:
  HeadAsset loadHead(const HeadParams&, const std::string&, const std::string&) const override {
    const CubeHead cube;
    HeadAsset h;
    for (const auto& v : cube.vertices) h.mesh.positions.push_back(v.cast<float>());
    h.mesh.indices = cube.indices;
    h.anchor = Eigen::Vector3d(0.0, -0.05, 0.0);
    return h;
  }
  std::optional<KeyframeTrack> loadMeshAnimation(const HeadParams&, const std::string&, const TrackOptions&,
                                                 std::string* error) const override {
    *error = "no mesh animation";
    return std::nullopt;
  }
};

}  // namespace ponyhop

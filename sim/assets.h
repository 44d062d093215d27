// What the simulation needs from files it cannot read itself: the head's mesh (its triangles,
// bounds and placement in the head's body frame) and a mesh file's own animation. sim/ links no
// importer: engine/asset_loader.h implements this with assimp; tests may hand in their own.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "physics/models/keyframes.h"
#include "sim/mesh_data.h"
#include "sim/scene.h"

namespace ponyhop {

// The head's mesh as the simulation sees it.
struct HeadAsset {
  MeshData mesh;                                               // in the mesh file's coordinates
  Eigen::Affine3d mesh_to_body = Eigen::Affine3d::Identity();  // HeadParams placement
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();            // ponytail anchor, body frame (m)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();            // centre of the head's bounds, body frame (m)
};

class AssetLoader {
 public:
  virtual ~AssetLoader() = default;
  // The head of `head`, read from `mesh_path` (already resolved). Throws InputError naming the
  // scene file and the field when it cannot be read.
  virtual HeadAsset loadHead(const HeadParams& head, const std::string& mesh_path,
                             const std::string& scene_path) const = 0;
  // head.animation.clip = "mesh": the mesh file's own animation as a C2 track. nullopt and *error.
  virtual std::optional<KeyframeTrack> loadMeshAnimation(const HeadParams& head, const std::string& mesh_path,
                                                         const TrackOptions& options, std::string* error) const = 0;
};

}  // namespace ponyhop

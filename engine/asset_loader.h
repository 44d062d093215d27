// The simulation's AssetLoader (sim/assets.h) on assimp: head meshes of any format assimp reads,
// placed by HeadParams (engine/mesh.h), and a mesh file's own animation (engine/animation_import.h).
#pragma once

#include "sim/assets.h"

namespace ponyhop {

class AssimpAssets final : public AssetLoader {
 public:
  HeadAsset loadHead(const HeadParams& head, const std::string& mesh_path,
                     const std::string& scene_path) const override;
  std::optional<KeyframeTrack> loadMeshAnimation(const HeadParams& head, const std::string& mesh_path,
                                                 const TrackOptions& options, std::string* error) const override;
};

// The loader the commands, the window and the tests use (one per process).
const AssetLoader& assimpAssets();

}  // namespace ponyhop

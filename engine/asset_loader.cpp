#include "engine/asset_loader.h"

#include "engine/animation_import.h"
#include "engine/mesh.h"
#include "sim/scene_io.h"

namespace ponyhop {

HeadAsset AssimpAssets::loadHead(const HeadParams& head, const std::string& mesh_path,
                                 const std::string& scene_path) const {
  HeadAsset a;
  std::string err;
  if (!loadMesh(mesh_path, a.mesh, &err)) throw SceneError(scene_path + ": head.mesh: " + err);
  a.mesh_to_body = meshToBody(head, a.mesh.bbox);
  a.anchor = meshPointToBody(head, a.mesh.bbox, head.anchor);
  return a;
}

std::optional<KeyframeTrack> AssimpAssets::loadMeshAnimation(const HeadParams& head, const std::string& mesh_path,
                                                             const TrackOptions& options, std::string* error) const {
  // The file's own animation, its keys taken as samples of the node's pose (metres, after the
  // same up-axis fix as the mesh).
  AnimationImportOptions import;
  import.y_up_to_z_up = head.up_axis == UpAxis::Y;
  return importAnimationTrack(mesh_path, import, options, error);
}

const AssetLoader& assimpAssets() {
  static const AssimpAssets loader;
  return loader;
}

}  // namespace ponyhop

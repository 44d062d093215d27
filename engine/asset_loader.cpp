#include "engine/asset_loader.h"

#include <cstdio>
#include <mutex>
#include <set>

#include "engine/animation_import.h"
#include "engine/mesh.h"
#include "sim/head_fit.h"
#include "sim/scene_io.h"

namespace ponyhop {

HeadAsset AssimpAssets::loadHead(const HeadParams& head, const std::string& mesh_path,
                                 const std::string& scene_path) const {
  HeadAsset a;
  std::string err;
  if (!loadMesh(mesh_path, a.mesh, &err)) throw InputError(scene_path + ": head.mesh: " + err);
  // Placement from the head itself (sim/head_fit.h).
  const HeadFit fit = fitHead(head, mesh_path, a.mesh);
  // The file's textures that cannot be read, and a head that is a guess. Each is said once a
  // process: the app reloads the head with every edit of the scene.
  std::vector<std::string> warnings = a.mesh.warnings;
  if (!fit.unsure.empty()) warnings.push_back(mesh_path + ": " + unsureFitMessage(fit, a.mesh));
  static std::mutex said_mutex;
  static std::set<std::string> said;
  for (const std::string& w : warnings) {
    const std::lock_guard<std::mutex> lock(said_mutex);
    if (said.insert(w).second) std::fprintf(stderr, "ponyhop: warning: head.mesh: %s\n", w.c_str());
  }
  // The file's own colours (textures, vertex colours, several materials) or head.color.
  if (head.materials == HeadMaterials::Color) a.mesh.dropMaterials();
  if (!head.scalp_hair) a.mesh.hair.clear();
  a.mesh_to_body = headMeshToBody(head, fit);
  a.anchor = a.mesh_to_body * headAnchorInMesh(head, fit, a.mesh);
  a.centre = a.mesh_to_body * fit.head_bounds.center().cast<double>();
  return a;
}

std::optional<KeyframeTrack> AssimpAssets::loadMeshAnimation(const HeadParams& head, const std::string& mesh_path,
                                                             const TrackOptions& options, std::string* error) const {
  // The file's own animation, its keys taken as samples of the node's pose (metres, after the
  // same up-axis fix as the mesh).
  AnimationImportOptions import;
  import.y_up_to_z_up =
      (head.up_axis == UpAxis::Auto ? detectUpAxis(mesh_path, MeshData{}, nullptr) : head.up_axis) == UpAxis::Y;
  return importAnimationTrack(mesh_path, import, options, error);
}

const AssetLoader& assimpAssets() {
  static const AssimpAssets loader;
  return loader;
}

}  // namespace ponyhop

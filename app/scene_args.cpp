#include "app/scene_args.h"

#include "engine/data_dir.h"
#include "engine/scene_io.h"

namespace ponyhop {

Scene SceneArgs::load() const {
  std::vector<Override> overrides;
  for (const auto& s : sets) overrides.push_back(parseOverride(s));
  return loadScene(resolveSceneFile(path), overrides);
}

}  // namespace ponyhop

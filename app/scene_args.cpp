#include "app/scene_args.h"

#include <cstdio>

#include "app/presets.h"
#include "sim/data_dir.h"
#include "sim/scene_io.h"

namespace ponyhop {

Scene SceneArgs::load() const {
  std::vector<Override> overrides;
  for (const auto& s : sets) overrides.push_back(parseOverride(s));
  const std::string file = resolveSceneFile(path);
  Scene scene = preset.empty() ? loadScene(file, overrides) : applyPreset(loadScene(file), preset, overrides);
  for (const auto& n : scene.notes) std::fprintf(stderr, "ponyhop: note: %s\n", n.c_str());
  return scene;
}

}  // namespace ponyhop

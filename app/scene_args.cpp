#include "app/scene_args.h"

#include "sim/scene_io.h"

namespace ponyhop {

Scene SceneArgs::load() const {
  std::vector<Override> overrides;
  for (const auto& s : sets) overrides.push_back(parseOverride(s));
  return loadScene(path, overrides);
}

}  // namespace ponyhop

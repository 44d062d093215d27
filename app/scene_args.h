// Command-line pieces shared by the subcommands that take a scene: SCENE, --set key=value...
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "sim/scene.h"

namespace ponyhop {

struct SceneArgs {
  std::string path;
  std::vector<std::string> sets;

  void add(CLI::App* cmd) {
    cmd->add_option("scene", path, "Scene file (JSON), e.g. assets/scenes/ponytail.json")->required();
    cmd->add_option("--set", sets, "Override a scene field: --set physics.dt=0.002 (repeatable)")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  }

  // Loads and validates; throws SceneError (message names the file, the key, what is allowed).
  Scene load() const;
};

}  // namespace ponyhop

// Command-line pieces shared by the subcommands that take a scene: SCENE, --set key=value...
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/scene.h"

namespace ponyhop {

// CLI11 checks for what CLI11 lets through: "" for a path or size (which would silently mean the
// default) and NaN (which passes CLI::Range, every comparison being false).
inline CLI::Validator nonEmpty() {
  return CLI::Validator([](std::string& s) { return s.empty() ? std::string("must not be empty") : std::string(); },
                        "NOT EMPTY");
}
inline CLI::Validator finiteIn(double lo, double hi) {
  char range[64];
  std::snprintf(range, sizeof(range), "[%g, %g]", lo, hi);
  return CLI::Validator(
      [lo, hi, r = std::string(range)](std::string& s) -> std::string {
        double v = 0.0;
        size_t used = 0;
        try {
          v = std::stod(s, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != s.size() || !(v >= lo && v <= hi)) {
          return "'" + s + "' is not a number in " + r;
        }
        return "";
      },
      "in " + std::string(range));
}

struct SceneArgs {
  std::string path;
  std::string preset;
  std::vector<std::string> sets;

  void add(CLI::App* cmd) {
    cmd->add_option("scene", path, "Scene file (JSON), e.g. assets/scenes/ponytail.json")->required();
    cmd->add_option("--set", sets, "Override a scene field: --set physics.dt=0.002 (repeatable)")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    cmd->add_option("--preset", preset,
                    "Lay a preset over the scene before --set: a name in assets/presets/ (silky, thick, wet, "
                    "stiff, bouncy) or a .json fragment");
  }

  // Loads the file, lays the preset over it, applies --set and validates; throws InputError
  // (the message names the file, the key, what is allowed).
  Scene load() const;
};

}  // namespace ponyhop

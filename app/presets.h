// Presets: scene-file fragments in assets/presets/NAME.json (for example {"chain": {"stiffness":
// ..., "damping": ...}}) laid over a scene. The panel loads them with one click, the commands
// that take a scene with `--preset NAME`. Fields the fragment leaves out keep the scene's values.
#pragma once

#include <string>
#include <vector>

#include "sim/scene.h"
#include "sim/scene_io.h"

namespace ponyhop {

// The presets shipped in assets/presets/, by name, sorted.
std::vector<std::string> presetNames();

// The file of a preset: NAME (assets/presets/NAME.json) or a path to a .json file. "" if none.
std::string presetPath(const std::string& name_or_path);

// The scene with the preset laid over it, then the overrides (as --set). Throws InputError naming
// the preset's file and the field (an unknown key, a value out of range, a section the scene does
// not have: a preset never adds a ponytail to a scene without one).
Scene applyPreset(const Scene& scene, const std::string& name_or_path, const std::vector<Override>& overrides = {});

// One line saying what a preset sets ("chain: stiffness, damping, ..."), for tooltips.
std::string presetSummary(const std::string& name_or_path);

}  // namespace ponyhop

// Scene files: JSON read and written through the Params structs' reflect() lists, so every field
// has one name, one default, one unit and one range for the file, `--set`, the panel and the docs.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sim/input_error.h"  // what the readers throw
#include "sim/scene.h"

namespace ponyhop {

// One `--set key=value` override. The value is parsed as JSON when it can be (numbers, true,
// [1,2,3], "text"), otherwise taken as a string: `--set head.mesh=my head.obj` works unquoted.
struct Override {
  std::string key;
  std::string value;
};
Override parseOverride(const std::string& key_equals_value);  // throws InputError

// Limits of scene and clip files (docs/RELIABILITY.md): a larger file or a deeper nesting of
// [ ] and { } is refused with the limit in the message, before the JSON is built.
inline constexpr size_t kMaxSceneFileBytes = 16u << 20;
inline constexpr int kMaxJsonDepth = 64;
// A chain longer than this on physics.solver = "dense" (O(n^3) per step) gets a note in
// Scene::notes with its cost.
inline constexpr int kDenseSolverMaxLinks = 32;

// Reads a scene file, applies the overrides, validates every field (types, ranges, unknown keys,
// files that must exist) and resolves relative paths. Throws InputError listing every problem.
Scene loadScene(const std::string& path, const std::vector<Override>& overrides = {});

// The same from the file's text (`source` names it in messages): the limits above, a key twice
// in one object, a number beyond a double's range are all InputErrors naming source and field.
Scene parseSceneText(const std::string& text, const std::string& source, const std::vector<Override>& overrides = {});

// The same from JSON already parsed (`source` names it in messages).
Scene parseScene(const nlohmann::json& j, const std::string& source, const std::vector<Override>& overrides = {});

// Every field of the scene, sections that exist only. Reading the result gives the same scene.
nlohmann::json sceneToJson(const Scene& scene);

// Writes the scene atomically (temporary file + rename). Throws InputError on failure.
void saveScene(const Scene& scene, const std::string& path);

// Checks a scene built or edited in code (the panel): ranges, cross-field rules. Throws InputError.
void validateScene(const Scene& scene, const std::string& source);

// A path from a scene (mesh, clip) resolved: absolute as is; otherwise relative to the working
// directory, then the scene file's folder, then ponyhop's data folder (sim/data_dir.h). "" when not found.
std::string resolveScenePath(const std::string& path, const std::string& scene_path);

// A clip file (assets/animations/*.json): {"mode": ..., "keys": [...]} with the fields of
// AnimationParams. Throws InputError naming the file and the key.
AnimationParams loadClipFile(const std::string& path);
AnimationParams parseClipText(const std::string& text, const std::string& source);

// The file of head.animation.clip: a bare name is assets/animations/NAME.json. "" when the clip
// is "", "mesh", or not found.
std::string resolveClipPath(const std::string& clip, const std::string& scene_path);

// The reference of every field (name, type, default, unit, range, help) as Markdown.
std::string sceneReferenceMarkdown();

}  // namespace ponyhop

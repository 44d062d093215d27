#include "app/presets.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "sim/data_dir.h"

namespace ponyhop {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const std::string kPresetDir = "assets/presets";

json readFragment(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the preset");
  json j;
  try {
    j = json::parse(in, nullptr, true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    throw InputError(path + ": not valid JSON: " + e.what());
  }
  if (!j.is_object()) throw InputError(path + ": a preset is a JSON object of scene sections, e.g. {\"chain\": {...}}");
  return j;
}

}  // namespace

std::vector<std::string> presetNames() {
  std::vector<std::string> names;
  std::error_code ec;
  // As resolveScenePath looks: the working directory first, then ponyhop's own assets (dataDir()).
  const std::string dir = fs::is_directory(kPresetDir, ec) ? kPresetDir : dataDir() + "/" + kPresetDir;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string presetPath(const std::string& name_or_path) {
  if (name_or_path.empty()) return "";
  const bool bare = name_or_path.find('/') == std::string::npos && fs::path(name_or_path).extension() != ".json";
  return resolveScenePath(bare ? kPresetDir + "/" + name_or_path + ".json" : name_or_path, "");
}

Scene applyPreset(const Scene& scene, const std::string& name_or_path, const std::vector<Override>& overrides) {
  const std::string path = presetPath(name_or_path);
  if (path.empty()) {
    std::string known;
    for (const std::string& n : presetNames()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("--preset " + name_or_path + ": no such preset (shipped: " + known +
                     "; or a path to a .json fragment)");
  }
  const json fragment = readFragment(path);
  json j = sceneToJson(scene);
  for (auto it = fragment.begin(); it != fragment.end(); ++it) {
    if (it.value().is_object() && !j.contains(it.key())) {
      throw InputError(path + ": the preset sets '" + it.key() + "', but the scene " +
                       (scene.path.empty() ? std::string("") : scene.path + " ") + "has no '" + it.key() +
                       "' section (a preset never adds one)");
    }
  }
  j.merge_patch(fragment);
  Scene out = parseScene(j, "preset " + path, overrides);
  out.path = scene.path;
  return out;
}

std::string presetSummary(const std::string& name_or_path) {
  const std::string path = presetPath(name_or_path);
  if (path.empty()) return "";
  try {
    const json j = readFragment(path);
    std::string s;
    for (auto it = j.begin(); it != j.end(); ++it) {
      s += (s.empty() ? "" : "; ") + it.key() + ":";
      if (it.value().is_object()) {
        for (auto f = it.value().begin(); f != it.value().end(); ++f) s += " " + f.key() + " " + f.value().dump();
      }
    }
    return s;
  } catch (const InputError& e) {
    return e.what();
  }
}

}  // namespace ponyhop

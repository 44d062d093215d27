#include "sim/scene_io.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <type_traits>

#include "physics/models/hopper.h"
#include "physics/validate.h"
#include "sim/data_dir.h"
#include "sim/input_file.h"

namespace ponyhop {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string formatNumber(double x) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.10g", x);
  return buf;
}

std::string vectorText(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "[%.10g, %.10g, %.10g]", v.x(), v.y(), v.z());
  return buf;
}

std::string rangeText(const FieldMeta& m) {
  const bool has_min = std::isfinite(m.min), has_max = std::isfinite(m.max);
  std::string unit = (m.unit && *m.unit) ? std::string(" ") + m.unit : "";
  if (has_min && has_max) return "in [" + formatNumber(m.min) + ", " + formatNumber(m.max) + "]" + unit;
  if (has_min) return ">= " + formatNumber(m.min) + unit;
  if (has_max) return "<= " + formatNumber(m.max) + unit;
  return unit.empty() ? "finite" : "finite," + unit;
}

template <class E>
std::string enumChoices() {
  std::string s;
  for (auto n : EnumNames<E>::names) {
    if (!s.empty()) s += ", ";
    s += '"' + std::string(n) + '"';
  }
  return s;
}

// A value as echoed in a message: at most ~80 characters, so a 10 MB bad value is not repeated.
std::string shortText(const std::string& s) {
  constexpr size_t kMax = 80;
  if (s.size() <= kMax) return s;
  return s.substr(0, kMax) + "... (" + std::to_string(s.size()) + " characters)";
}
std::string shortDump(const json& j) {
  // replace: a string with invalid UTF-8 must not throw while an error is being reported
  return shortText(j.dump(-1, ' ', false, json::error_handler_t::replace));
}

// JSON text read with limits: nesting depth (the DOM's copy, dump and destruction recurse, so an
// unbounded depth is a stack overflow), no key twice in one object (nlohmann keeps the last one
// silently), and a number that does not fit a double named by its field.
json parseJsonLimited(const std::string& text, const std::string& source) {
  std::vector<std::string> path;            // keys from the root to the current value
  std::vector<std::set<std::string>> seen;  // keys met in each open object
  const auto where = [&path]() {
    std::string p;
    for (const auto& k : path) {
      if (!k.empty()) p += (p.empty() ? "" : ".") + k;  // "" marks an array level
    }
    return p;
  };
  const json::parser_callback_t cb = [&](int depth, json::parse_event_t event, json& parsed) -> bool {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        if (depth >= kMaxJsonDepth) {
          throw InputError(source + ": " + (path.empty() ? std::string("the document") : where()) +
                           ": nested deeper than " + std::to_string(kMaxJsonDepth) +
                           " levels of [ ] and { } (the limit for scene and clip files)");
        }
        seen.resize(size_t(depth) + 1);
        seen[size_t(depth)].clear();
        path.resize(size_t(depth));
        if (event == json::parse_event_t::array_start) path.emplace_back("");
        break;
      case json::parse_event_t::key: {
        const std::string k = parsed.get<std::string>();
        path.resize(size_t(depth));
        path.back() = k;
        if (!seen[size_t(depth) - 1].insert(k).second) {
          throw InputError(source + ": " + where() + ": the key appears twice in one object (which one is meant?)");
        }
        break;
      }
      default:
        break;
    }
    return true;
  };
  try {
    return json::parse(text, cb, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const json::out_of_range& e) {
    // -1e400: nlohmann's "number overflow parsing '-1e400'" names neither file nor field.
    std::string msg = e.what();
    const auto q = msg.find("number overflow");
    if (q != std::string::npos) msg = msg.substr(q);
    throw InputError(source + ": " + (path.empty() ? std::string("the document") : where()) + ": " + shortText(msg) +
                     " (numbers must be finite doubles, |x| < 1.8e308)");
  } catch (const json::exception& e) {
    throw InputError(source + ": not valid JSON: " + shortText(e.what()));
  }
}

// Reads one JSON object into a reflectable struct, collecting every problem it finds.
class JsonReader {
 public:
  JsonReader(const json& j, std::string prefix, std::vector<std::string>& errors)
      : j_(j), prefix_(std::move(prefix)), errors_(errors) {}

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& meta) {
    known_.insert(name);
    auto it = j_.find(name);
    if (it == j_.end()) return;
    read(*it, field, meta, prefix_ + name);
  }

  // After reflect(): every key of the object must have been a field.
  void checkUnknown() {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      if (known_.count(it.key())) continue;
      std::string list;
      for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
      errors_.push_back(prefix_ + it.key() + ": unknown key (allowed here: " + list + ")");
    }
  }

  template <class T>
  static void readStruct(const json& j, T& out, const std::string& key, std::vector<std::string>& errors) {
    if (!j.is_object()) {
      errors.push_back(key + ": must be an object { ... }, got " + std::string(j.type_name()));
      return;
    }
    JsonReader r(j, key.empty() ? "" : key + ".", errors);
    out.reflect(r);
    r.checkUnknown();
  }

 private:
  void bad(const std::string& key, const std::string& what, const json& got) {
    errors_.push_back(key + ": must be " + what + ", got " + shortDump(got));
  }

  template <class T>
  void read(const json& j, T& field, const FieldMeta& meta, const std::string& key) {
    if constexpr (std::is_same_v<T, bool>) {
      if (!j.is_boolean()) return bad(key, "true or false", j);
      field = j.get<bool>();
    } else if constexpr (std::is_same_v<T, int>) {
      if (!j.is_number_integer()) return bad(key, "a whole number " + rangeText(meta), j);
      const auto x = j.get<long long>();
      if (!inRange(static_cast<double>(x), meta)) return bad(key, "a whole number " + rangeText(meta), j);
      field = static_cast<int>(x);
    } else if constexpr (std::is_same_v<T, double>) {
      if (!j.is_number()) return bad(key, "a number " + rangeText(meta), j);
      const double x = j.get<double>();
      if (!inRange(x, meta)) return bad(key, "a number " + rangeText(meta), j);
      field = x;
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (!j.is_string()) return bad(key, "a string", j);
      field = j.get<std::string>();
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      const std::string what = "an array of 3 numbers, each " + rangeText(meta);
      if (!j.is_array() || j.size() != 3) return bad(key, what, j);
      Eigen::Vector3d v;
      for (int i = 0; i < 3; ++i) {
        if (!j[i].is_number()) return bad(key, what, j);
        v[i] = j[i].get<double>();
        if (!inRange(v[i], meta)) return bad(key, what, j);
      }
      field = v;
    } else if constexpr (std::is_enum_v<T>) {
      if (!j.is_string() || !enumFromName(j.get<std::string>(), field)) {
        return bad(key, "one of " + enumChoices<T>(), j);
      }
    } else if constexpr (IsOptional<T>::value) {
      if (j.is_null()) {
        field.reset();
        return;
      }
      if (!field) field.emplace();
      read(j, *field, meta, key);
    } else if constexpr (IsVector<T>::value) {
      if (!j.is_array()) return bad(key, "an array", j);
      T out(j.size());
      for (size_t i = 0; i < j.size(); ++i) read(j[i], out[i], meta, key + "." + std::to_string(i));
      field = std::move(out);
    } else {
      readStruct(j, field, key, errors_);
    }
  }

  const json& j_;
  std::string prefix_;
  std::vector<std::string>& errors_;
  std::set<std::string> known_;
};

// Writes a reflectable struct as JSON: every field, optional sections only when present.
class JsonWriter {
 public:
  explicit JsonWriter(json& j) : j_(j) {}

  template <class T>
  void operator()(const char* name, const T& field, const FieldMeta&) {
    if constexpr (IsOptional<T>::value) {
      if (field) j_[name] = write(*field);
    } else {
      j_[name] = write(field);
    }
  }

  template <class T>
  static json write(const T& field) {
    if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, int> || std::is_same_v<T, double> ||
                  std::is_same_v<T, std::string>) {
      return field;
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      return json::array({field.x(), field.y(), field.z()});
    } else if constexpr (std::is_enum_v<T>) {
      return std::string(enumName(field));
    } else if constexpr (IsVector<T>::value) {
      json a = json::array();
      for (const auto& e : field) a.push_back(write(e));
      return a;
    } else {
      json o = json::object();
      JsonWriter w(o);
      const_cast<T&>(field).reflect(w);  // reflect() only reads through a writer
      return o;
    }
  }

 private:
  json& j_;
};

// Range checks of a struct edited in code (the panel), through the same field list.
class RangeChecker {
 public:
  RangeChecker(std::string prefix, std::vector<std::string>& errors) : prefix_(std::move(prefix)), errors_(errors) {}

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& meta) {
    check(field, meta, prefix_ + name);
  }

 private:
  template <class T>
  void check(T& field, const FieldMeta& meta, const std::string& key) {
    if constexpr (std::is_same_v<T, int> || std::is_same_v<T, double>) {
      const double x = static_cast<double>(field);
      if (!inRange(x, meta)) {
        errors_.push_back(key + ": must be " + rangeText(meta) + ", got " + formatNumber(x));
      }
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      for (int i = 0; i < 3; ++i) {
        if (!inRange(field[i], meta)) {
          errors_.push_back(key + ": each component must be " + rangeText(meta));
          break;
        }
      }
    } else if constexpr (IsOptional<T>::value) {
      if (field) check(*field, meta, key);
    } else if constexpr (IsVector<T>::value) {
      for (size_t i = 0; i < field.size(); ++i) check(field[i], meta, key + "." + std::to_string(i));
    } else if constexpr (std::is_class_v<T> && !std::is_same_v<T, std::string>) {
      RangeChecker c(key + ".", errors_);
      field.reflect(c);
    }
  }

  std::string prefix_;
  std::vector<std::string>& errors_;
};

std::string joinErrors(const std::string& source, const std::vector<std::string>& errors) {
  std::string msg = source + ": " + std::to_string(errors.size()) + (errors.size() == 1 ? " problem" : " problems");
  for (const auto& e : errors) msg += "\n  " + e;
  return msg;
}

// Sets `value` at the dotted `key` inside `j`, creating objects on the way.
void applyOverride(json& j, const Override& o) {
  json* node = &j;
  std::stringstream ss(o.key);
  std::string part;
  std::vector<std::string> parts;
  while (std::getline(ss, part, '.')) parts.push_back(part);
  for (size_t i = 0; i < parts.size(); ++i) {
    const std::string& p = parts[i];
    const bool last = i + 1 == parts.size();
    std::string list;  // the key of the value `p` indexes (goals for goals.0.t)
    for (size_t k = 0; k < i; ++k) list += (k ? "." : "") + parts[k];
    if (node->is_array()) {
      char* end = nullptr;
      const long idx = std::strtol(p.c_str(), &end, 10);
      if (*end != '\0' || idx < 0 || static_cast<size_t>(idx) >= node->size()) {
        throw InputError("--set " + o.key + ": '" + p + "' is not an index of that list (" +
                         (node->empty() ? "it is empty" : "0.." + std::to_string(node->size() - 1)) +
                         "); a list is given whole: --set " + list + "='[...]', or its elements in the scene file");
      }
      node = &(*node)[static_cast<size_t>(idx)];
    } else {
      if (node->is_null() && i > 0 && !p.empty() &&
          std::all_of(p.begin(), p.end(), [](char c) { return c >= '0' && c <= '9'; })) {
        // An index into a list the file does not have (goals.0.t on a scene without goals): not a
        // section to create, and not "must be an array" further on.
        throw InputError("--set " + o.key + ": '" + p +
                         "' is not an index of that list (the scene has none); a list is "
                         "given whole: --set " +
                         list + "='[...]', or its elements in the scene file");
      }
      if (node->is_null()) *node = json::object();
      if (!node->is_object()) {
        throw InputError("--set " + o.key + ": '" + p + "' is inside a value that is not a section");
      }
      node = &(*node)[p];
    }
    if (last) {
      json v;
      try {
        v = parseJsonLimited(o.value, "--set " + o.key);
      } catch (const InputError& e) {
        // Unquoted text is a string; JSON that is too deep or has a repeated key is an error.
        const std::string m = e.what();
        if (m.find("nested deeper") != std::string::npos || m.find("appears twice") != std::string::npos) throw;
        v = o.value;
        try {
          (void)v.dump();  // JSON strings are UTF-8: refuse here what no writer could write
        } catch (const json::type_error&) {
          throw InputError("--set " + o.key + ": the value is not valid UTF-8 text");
        }
      }
      *node = v;
    }
  }
}

bool sectionPresent(const json& j, const std::string& name) { return j.contains(name) && !j[name].is_null(); }

const char* kOptionalSections[] = {"head", "anchor", "chain", "hopper"};

// Dense is O(n^3) per step: a long chain on it would run for days without a word. The default
// (tree) is O(n); a dense solver the user chose is kept, with its cost said up front.
void noteDenseCost(Scene& scene) {
  if (!chainCount(scene) || scene.physics.solver != SolverKind::Dense) return;
  int n = 0;  // every chain's links are in the one dense system
  for (size_t i = 0; i < chainCount(scene); ++i) n += chainSection(scene, i).links;
  if (n > kDenseSolverMaxLinks) {
    // Measured (docs/SOLVERS.md): about 48 ms per step at 128 links, growing as n^3.
    const double ms = 48.0 * std::pow(n / 128.0, 3.0);
    char buf[160];
    std::snprintf(buf, sizeof(buf), "about %.3g s per step (%.3g h per simulated second at dt %.3g s)", ms / 1000.0,
                  ms / 1000.0 / scene.physics.dt / 3600.0, scene.physics.dt);
    scene.notes.push_back("physics.solver = \"dense\" with " + std::to_string(n) + " links: O(n^3), " + buf +
                          "; \"tree\" (the default) gives the same results in O(n)");
  }
}

}  // namespace

Override parseOverride(const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw InputError("--set " + kv + ": expected key=value, e.g. --set physics.dt=0.002");
  }
  return {kv.substr(0, eq), kv.substr(eq + 1)};
}

std::string resolveScenePath(const std::string& path, const std::string& scene_path) {
  if (path.empty()) return "";
  std::error_code ec;
  const fs::path p(path);
  if (p.is_absolute()) return fs::is_regular_file(p, ec) ? path : "";
  if (fs::is_regular_file(p, ec)) return path;
  if (!scene_path.empty()) {
    const fs::path q = fs::path(scene_path).parent_path() / p;
    if (fs::is_regular_file(q, ec)) return q.string();
  }
  if (dataDir().empty()) return "";
  const fs::path r = fs::path(dataDir()) / p;
  if (fs::is_regular_file(r, ec)) return r.string();
  return "";
}

Scene parseScene(const json& j_in, const std::string& source, const std::vector<Override>& overrides) {
  json j = j_in;
  if (!j.is_object()) throw InputError(source + ": a scene file must be a JSON object { ... }");
  // A mesh-space anchor belongs to the mesh it was written for: another mesh given by --set alone
  // takes its anchor from its own bounds (head.anchor_in_bounds).
  bool anchor_given = false;
  for (const auto& o : overrides) anchor_given = anchor_given || o.key == "head" || o.key.rfind("head.anchor", 0) == 0;
  const bool mesh_anchor = j.contains("head") && j["head"].is_object() && j["head"].contains("anchor_space") &&
                           j["head"]["anchor_space"] == "mesh" && j["head"].contains("mesh");
  for (const auto& o : overrides) {
    const std::string section = o.key.substr(0, o.key.find('.'));
    for (const char* opt : kOptionalSections) {
      if (section == opt && !sectionPresent(j, opt) && o.key != section) {
        throw InputError("--set " + o.key + ": this scene has no '" + section +
                         "' section (a scene file names what exists)");
      }
    }
    applyOverride(j, o);
  }
  std::string anchor_note;
  if (mesh_anchor && !anchor_given && j["head"]["mesh"] != j_in["head"]["mesh"]) {
    j["head"]["anchor_space"] = "bounds";
    anchor_note = "head.anchor is in the coordinates of the scene's own mesh (" +
                  shortText(j_in["head"]["mesh"].dump()) + "); on " + shortText(j["head"]["mesh"].dump()) +
                  " the ponytail is anchored from its bounds (head.anchor_in_bounds); --set head.anchor_space=mesh "
                  "keeps the file's anchor";
  }
  Scene scene;
  std::vector<std::string> errors;
  JsonReader::readStruct(j, scene, "", errors);
  if (!errors.empty()) {
    // Name the override that caused a problem, so the user knows it was not the file.
    for (auto& e : errors) {
      for (const auto& o : overrides) {
        if (e.rfind(o.key, 0) == 0) {
          e = "(from --set " + o.key + "=" + shortText(o.value) + ") " + e;
          break;
        }
      }
    }
    throw InputError(joinErrors(source, errors));
  }
  scene.path = source;
  validateScene(scene, source);
  noteDenseCost(scene);
  if (!anchor_note.empty()) scene.notes.push_back(anchor_note);
  return scene;
}

Scene parseSceneText(const std::string& text, const std::string& source, const std::vector<Override>& overrides) {
  return parseScene(parseJsonLimited(text, source), source, overrides);
}

Scene loadScene(const std::string& path, const std::vector<Override>& overrides) {
  std::string text, err;
  if (!readInputFile(path, kMaxSceneFileBytes, "scene file", &text, &err)) throw InputError(err);
  Scene scene = parseSceneText(text, path, overrides);
  scene.path = path;
  return scene;
}

std::string resolveClipPath(const std::string& clip, const std::string& scene_path) {
  if (clip.empty() || clip == "mesh") return "";
  const bool bare = clip.find('/') == std::string::npos && clip.find('.') == std::string::npos;
  return resolveScenePath(bare ? "assets/animations/" + clip + ".json" : clip, scene_path);
}

AnimationParams parseClipText(const std::string& text, const std::string& source) {
  const json j = parseJsonLimited(text, source);
  AnimationParams clip;
  std::vector<std::string> errors;
  JsonReader::readStruct(j, clip, "", errors);
  if (!errors.empty()) throw InputError(joinErrors(source, errors));
  return clip;
}

AnimationParams loadClipFile(const std::string& path) {
  std::string text, err;
  if (!readInputFile(path, kMaxSceneFileBytes, "clip file", &text, &err)) throw InputError(err);
  return parseClipText(text, path);
}

json sceneToJson(const Scene& scene) { return JsonWriter::write(scene); }

void saveScene(const Scene& scene, const std::string& path) {
  std::error_code ec0;
  if (fs::exists(path, ec0) && !fs::is_regular_file(path, ec0)) {
    throw InputError(path + ": is not a regular file (a folder or a device); the scene is not saved there");
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(path + ": cannot write the scene file");
    out << sceneToJson(scene).dump(2) << "\n";
    if (!out) throw InputError(path + ": write failed");
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw InputError(path + ": cannot replace the file: " + ec.message());
}

void validateScene(const Scene& scene_in, const std::string& source) {
  Scene scene = scene_in;  // RangeChecker visits through non-const reflect()
  std::vector<std::string> errors;
  RangeChecker checker("", errors);
  scene.reflect(checker);
  if (scene.head) {
    if (resolveScenePath(scene.head->mesh, scene.path).empty()) {
      errors.push_back("head.mesh: file not found: \"" + scene.head->mesh +
                       "\" (looked in the working directory, beside the scene and in the repository)");
    }
    const auto& h = *scene.head;
    if (h.box_min != h.box_max && !(h.box_max.array() > h.box_min.array()).all()) {
      errors.push_back(
          "head.box_max: must exceed head.box_min on every axis (x, y, z) to pick the head by hand, or "
          "equal it to find the head from the mesh (got min " +
          vectorText(h.box_min) + ", max " + vectorText(h.box_max) + ")");
    }
    const auto& a = scene.head->animation;
    if (!a.clip.empty() && a.clip != "mesh") {
      if (resolveClipPath(a.clip, scene.path).empty()) {
        errors.push_back("head.animation.clip: no clip \"" + a.clip +
                         "\" (a name in assets/animations/, a clip file, \"mesh\", or \"\" for keys)");
      }
    }
  }
  const size_t hopper_count = (scene.hopper ? 1 : 0) + scene.hoppers.size();
  for (size_t i = 0; i < chainCount(scene); ++i) {
    const auto& c = chainSection(scene, i);
    const std::string key = chainKey(scene, i);
    if (c.direction.norm() < 1e-9) errors.push_back(key + ".direction: must not be the zero vector");
    if (c.attach == ChainAttach::Head && !scene.head) {
      errors.push_back(key + ".attach: \"head\" needs a head section in the scene");
    }
    if (c.attach == ChainAttach::Anchor && !scene.anchor) {
      errors.push_back(key + ".attach: \"anchor\" needs an anchor section in the scene");
    }
    if (const ChainListSection* listed = listedChain(scene, i)) {
      if (c.attach == ChainAttach::Hopper && size_t(listed->hopper) >= hopper_count) {
        errors.push_back(key + ".hopper: " + std::to_string(listed->hopper) +
                         " is not a hopper of this scene (it has " + std::to_string(hopper_count) +
                         ", counted from 0: hopper, then hoppers)");
      }
    } else if (c.attach == ChainAttach::Hopper && !scene.hopper) {
      errors.push_back(key + ".attach: \"hopper\" needs a hopper section in the scene");
    }
  }
  for (size_t j = 0; j < scene.joints.size(); ++j) {
    const JointSection& joint = scene.joints[j];
    const std::string key = "joints." + std::to_string(j);
    bool fixed = true;  // both ends on bodies that do not move
    for (const auto& [end, side] : {std::pair<const JointEnd*, const char*>{&joint.a, ".a"}, {&joint.b, ".b"}}) {
      const std::string k = key + side;
      switch (end->body) {
        case JointBody::World:
          break;
        case JointBody::Head:
          if (!scene.head) errors.push_back(k + ".body: \"head\" needs a head section in the scene");
          break;
        case JointBody::Chain:
          fixed = false;
          if (size_t(end->chain) >= chainCount(scene)) {
            errors.push_back(k + ".chain: " + std::to_string(end->chain) + " is not a chain of this scene (it has " +
                             std::to_string(chainCount(scene)) + ", counted from 0: chain, then chains)");
          } else if (end->link >= chainSection(scene, size_t(end->chain)).links) {
            errors.push_back(k + ".link: " + std::to_string(end->link) + " is not a link of " +
                             chainKey(scene, size_t(end->chain)) + " (it has " +
                             std::to_string(chainSection(scene, size_t(end->chain)).links) + "; -1: the last)");
          }
          break;
        case JointBody::Hopper:
          fixed = false;
          if (size_t(end->hopper) >= hopper_count) {
            errors.push_back(k + ".hopper: " + std::to_string(end->hopper) + " is not a hopper of this scene (it has " +
                             std::to_string(hopper_count) + ")");
          }
          break;
      }
    }
    if (fixed) errors.push_back(key + ": both ends are on bodies that do not move (the world or the head)");
    if (joint.type == JointType::Hinge && !(joint.axis.norm() > 1e-9)) {
      errors.push_back(key + ".axis: a hinge needs its axis (a non-zero vector, world, at t = 0)");
    }
  }
  if (scene.collision && !scene.collision->head) {
    const auto& c = *scene.collision;
    if (c.self || c.joint_cone > 0.0 || c.joint_twist > 0.0) {
      errors.push_back(
          "collision: self, joint_cone and joint_twist act on the ponytail the head collision builds: they "
          "need collision.head true (collision.head false builds nothing)");
    }
  }
  if (scene.terrain && !scene.hopper && scene.hoppers.empty()) {
    errors.push_back("terrain: the scene has no hopper (the boxes are ground for the hoppers' toes and bodies)");
  }
  if (scene.collision && scene.collision->ground && !scene.hopper && scene.hoppers.empty()) {
    errors.push_back("collision.ground: the scene has no hopper (it makes the hoppers' bodies and legs collide)");
  }
  if (scene.collision && (scene.collision->head || scene.collision->ground)) {
    // collision.head is on by default: a scene that asks only for ground contacts needs no head.
    bool head_chain = false;
    for (size_t i = 0; i < chainCount(scene); ++i)
      head_chain = head_chain || (chainSection(scene, i).attach == ChainAttach::Head && scene.head);
    if (scene.collision->head && !head_chain && !scene.collision->ground) {
      errors.push_back(
          "collision.head: the ponytail collides with the head only when chain.attach is \"head\" (or a chains "
          "entry's attach) and the scene has a head (set collision.head false, or leave the collision section out)");
    }
  }
  {
    // camera.follow names a body the scene has ("" = the scene's main body).
    const std::string& f = scene.camera.follow;
    const bool has_hopper = scene.hopper || !scene.hoppers.empty();
    const bool exists = f.empty() || (f == "head" && scene.head) || (f == "hopper" && has_hopper) ||
                        (f == "chain" && chainCount(scene));
    if (!exists) {
      std::string have;
      for (const auto& [name, present] : {std::pair<const char*, bool>{"head", bool(scene.head)},
                                          {"hopper", has_hopper},
                                          {"chain", chainCount(scene) > 0}}) {
        if (present) have += std::string(have.empty() ? "" : ", ") + '"' + name + '"';
      }
      errors.push_back("camera.follow: \"" + shortText(f) + "\" is not a body of this scene (allowed: \"\"" +
                       (have.empty() ? "" : ", " + have) + ")");
    }
  }
  if (errors.empty()) {
    // Physical sense beyond the ranges (leg lengths in order, the foot above the ground, ...).
    if (scene.hopper) {
      if (Status s = validate(*scene.hopper); !s.ok()) errors.push_back(s.message());
    }
    for (size_t i = 0; i < scene.hoppers.size(); ++i) {
      if (Status s = validate(scene.hoppers[i], "hoppers." + std::to_string(i)); !s.ok()) errors.push_back(s.message());
    }
  }
  if (const PhysicsParams& p = scene.physics; p.stabilization == Stabilization::Velocity) {
    // Velocity-level joints: symplectic Euler's in the multiplier solvers (physics/validate.cpp),
    // said with the file's other problems rather than when the world is built.
    if (!(p.adaptive_joints > 0 || p.adaptive_tolerance > 0.0)) {
      if (Status s = validate(p, "physics"); !s.ok()) errors.push_back(s.message());
    }
  }
  if (const PhysicsParams& p = scene.physics; p.adaptive_joints > 0 || p.adaptive_tolerance > 0.0) {
    // Adaptive dynamics (docs/SOLVERS.md): the reduced solver only, and no more joints than the
    // chain has (a scene on that solver has no other joints: the hoppers need contact rows).
    if (Status s = validate(p, "physics"); !s.ok()) errors.push_back(s.message());
    if (scene.chain && p.adaptive_joints > scene.chain->links) {
      errors.push_back("physics.adaptive_joints: " + std::to_string(p.adaptive_joints) + " is more than the " +
                       std::to_string(scene.chain->links) + " joints of the chain (allowed: 0 to chain.links)");
    }
  }
  checkGoals(scene, errors);
  if (scene.render.width % 2 || scene.render.height % 2) {
    // H.264 in yuv420p needs even sizes; keep every output consistent with the video.
    errors.push_back("render.width/height: must be even (got " + std::to_string(scene.render.width) + "x" +
                     std::to_string(scene.render.height) + ")");
  }
  if (!errors.empty()) throw InputError(joinErrors(source, errors));
}

namespace {

class DocWriter {
 public:
  DocWriter(std::string prefix, std::string& out) : prefix_(std::move(prefix)), out_(out) {}

  template <class T>
  void operator()(const char* name, T& field, const FieldMeta& meta) {
    doc(field, meta, prefix_ + name);
  }

 private:
  template <class T>
  static std::string typeName() {
    if constexpr (std::is_same_v<T, bool>)
      return "bool";
    else if constexpr (std::is_same_v<T, int>)
      return "integer";
    else if constexpr (std::is_same_v<T, double>)
      return "number";
    else if constexpr (std::is_same_v<T, std::string>)
      return "string";
    else if constexpr (std::is_same_v<T, Eigen::Vector3d>)
      return "[x, y, z]";
    else if constexpr (std::is_enum_v<T>)
      return enumChoices<T>();
    else
      return "";
  }

  template <class T>
  void doc(T& field, const FieldMeta& meta, const std::string& key) {
    if constexpr (IsOptional<T>::value) {
      out_ += "\n### `" + key + "` (optional section: present = built)\n\n" + meta.help +
              "\n\n| key | type | default | allowed | meaning |\n|---|---|---|---|---|\n";
      typename T::value_type def{};
      DocWriter w(key + ".", out_);
      def.reflect(w);
    } else if constexpr (IsVector<T>::value) {
      out_ += "| `" + key + "` | list | [] | | " + meta.help + " |\n";
      typename T::value_type def{};
      DocWriter w(key + ".N.", out_);
      def.reflect(w);
    } else if constexpr (std::is_class_v<T> && !std::is_same_v<T, std::string> && !std::is_same_v<T, Eigen::Vector3d>) {
      DocWriter w(key + ".", out_);
      field.reflect(w);
    } else {
      std::string range;
      if constexpr (std::is_same_v<T, int> || std::is_same_v<T, double> || std::is_same_v<T, Eigen::Vector3d>) {
        range = rangeText(meta);
      }
      out_ += "| `" + key + "` | " + typeName<T>() + " | `" + JsonWriter::write(field).dump() + "` | " + range + " | " +
              meta.help + " |\n";
    }
  }

  std::string prefix_;
  std::string& out_;
};

}  // namespace

std::string sceneReferenceMarkdown() {
  std::string out = "| key | type | default | allowed | meaning |\n|---|---|---|---|---|\n";
  Scene scene;
  DocWriter w("", out);
  scene.reflect(w);
  return out;
}

}  // namespace ponyhop

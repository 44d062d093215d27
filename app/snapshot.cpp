#include "app/snapshot.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "app/ui_headless.h"
#include "engine/gl_context.h"
#include "engine/render_session.h"
#include "engine/scene_draw.h"
#include "sim/scene_io.h"

namespace ponyhop {

namespace fs = std::filesystem;

namespace {

constexpr const char* kShotKeys = "t, size, threshold, max_share, subject, min_subject, wait, ui";

// Splits a line into tokens at white space; "..." groups (quotes removed); # starts a comment.
std::vector<std::string> tokenize(const std::string& line, std::string* error) {
  std::vector<std::string> out;
  std::string cur;
  bool in_token = false, quoted = false;
  for (char c : line) {
    if (quoted) {
      if (c == '"')
        quoted = false;
      else
        cur += c;
      continue;
    }
    if (c == '#' && !in_token) break;
    if (c == ' ' || c == '\t' || c == '\r') {
      if (in_token) out.push_back(cur);
      cur.clear();
      in_token = false;
      continue;
    }
    in_token = true;
    if (c == '"')
      quoted = true;
    else
      cur += c;
  }
  if (quoted) *error = "a quote \" is not closed";
  if (in_token) out.push_back(cur);
  return out;
}

bool parseNumber(const std::string& s, double& v) {
  if (s.empty()) return false;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(v);
}

std::string partName(unsigned part) {
  switch (part) {
    case SceneDraw::kHead:
      return "head";
    case SceneDraw::kChain:
      return "chain";
    case SceneDraw::kHopper:
      return "hopper";
  }
  return "everything";
}

unsigned partBit(const std::string& name) {
  if (name == "head") return SceneDraw::kHead;
  if (name == "chain" || name == "ponytail") return SceneDraw::kChain;
  if (name == "hopper") return SceneDraw::kHopper;
  return 0;
}

unsigned sceneParts(const Scene& s) {
  return (s.head ? SceneDraw::kHead : 0u) | (chainCount(s) ? SceneDraw::kChain : 0u) |
         (s.hopper || !s.hoppers.empty() ? SceneDraw::kHopper : 0u);
}

// Applies one `key=value` option to a shot; "" or the problem.
std::string applyOption(Shot& shot, const std::string& token) {
  const size_t eq = token.find('=');
  if (eq == std::string::npos || eq == 0) {
    return "'" + token + "': expected key=value (shot options: " + kShotKeys + "; a key with a dot is a scene field)";
  }
  const std::string key = token.substr(0, eq), value = token.substr(eq + 1);
  if (key.find('.') != std::string::npos) {
    shot.sets.push_back(token);
    return "";
  }
  double v = 0.0;
  if (key == "t") {
    if (!parseNumber(value, v) || v < 0.0 || v > 1e6)
      return "t=" + value + ": a time in seconds in [0, 1e6] is expected";
    shot.t = v;
  } else if (key == "size") {
    int w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(value.c_str(), "%dx%d%c", &w, &h, &tail) != 2)
      return "size=" + value + ": expected WIDTHxHEIGHT, e.g. 320x180";
    shot.width = w;
    shot.height = h;
  } else if (key == "threshold" || key == "max_share" || key == "min_subject") {
    if (!parseNumber(value, v) || v < 0.0 || v > 1.0) return key + "=" + value + ": a number in [0, 1] is expected";
    (key == "threshold" ? shot.diff.threshold : key == "max_share" ? shot.diff.max_diff_share : shot.min_subject) = v;
  } else if (key == "subject") {
    shot.subject.clear();
    shot.check_subject = value != "none";
    if (!shot.check_subject) return "";
    std::stringstream ss(value);
    for (std::string part; std::getline(ss, part, '+');) {
      if (!partBit(part))
        return "subject=" + value + ": '" + part + "' is not a subject (head, chain, hopper, none; join with +)";
      shot.subject.push_back(part);
    }
  } else if (key == "wait") {
    if (value != "stance" && value != "flight" && value != "none") return "wait=" + value + ": stance, flight or none";
    shot.wait = value == "none" ? "" : value;
  } else if (key == "ui") {
    if (value != "panel" && value != "none") return "ui=" + value + ": panel or none";
    shot.panel = value == "panel";
  } else {
    return "'" + key + "' is not a shot option (" + kShotKeys + "); scene fields have a dot: render.samples=1";
  }
  return "";
}

Image renderPanelShot(const Scene& scene, double t, std::string* renderer) {
  HeadlessUi ui(scene, scene.render.width, scene.render.height);
  ui.sim().readouts().show_wall_clock = false;  // measured times differ run to run
  UiInput in;
  ui.frame(in, nullptr, 0.0);  // lay the widgets out once
  Image img;
  img.width = ui.width();
  img.height = ui.height();
  ui.frame(in, &img.rgba, t);
  *renderer = glRendererName() + " / " + glVersionString();
  return img;
}

// Steps a hopper scene from its time on to the first stance (bottom) or flight (past apex) moment.
std::string waitFor(Sim& sim, const std::string& wait) {
  const Hopper* h = sim.hopper();
  if (!h) return "wait=" + wait + ": the scene has no hopper";
  const bool stance = wait == "stance";
  auto reached = [&] {
    const double vz = h->centerOfMassVelocity(sim.world()).z();
    return stance ? h->inContact() && vz >= 0.0 : !h->inContact() && vz <= 0.0;
  };
  const double limit = sim.time() + 3.0;
  while (sim.ok() && sim.time() < limit && !reached()) sim.step();
  if (!sim.ok()) return "the simulation stopped: " + sim.status();
  if (!reached()) return "no " + wait + " moment within 3 s after t";
  return "";
}

bool writeText(const std::string& path, const std::string& text) {
  std::ofstream f(path + ".tmp");
  f << text;
  f.close();
  if (!f) return false;
  std::error_code ec;
  fs::rename(path + ".tmp", path, ec);
  return !ec;
}

}  // namespace

bool inCi() {
  const char* ci = std::getenv("CI");
  return ci && *ci && std::strcmp(ci, "0") != 0 && std::strcmp(ci, "false") != 0;
}

Scene shotScene(const Shot& shot) {
  std::vector<Override> o;
  for (const auto& s : shot.sets) o.push_back(parseOverride(s));
  if (shot.width > 0) o.push_back({"render.width", std::to_string(shot.width)});
  if (shot.height > 0) o.push_back({"render.height", std::to_string(shot.height)});
  return loadScene(shot.scene_path, o);
}

ShotList loadShotList(const std::string& path, const std::string& golden_dir) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the shot list");
  ShotList list;
  list.path = path;
  list.golden_dir = golden_dir.empty() ? fs::path(path).parent_path().string() : golden_dir;
  if (list.golden_dir.empty()) list.golden_dir = ".";
  Shot defaults;
  std::set<std::string> names;
  std::string problems;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const std::string where = path + ":" + std::to_string(n) + ": ";
    std::string err;
    const std::vector<std::string> tok = tokenize(line, &err);
    if (!err.empty()) {
      problems += where + err + "\n";
      continue;
    }
    if (tok.empty()) continue;
    const bool is_defaults = tok[0] == "defaults";
    Shot shot = defaults;
    shot.line = n;
    size_t first_option = 1;
    if (!is_defaults) {
      shot.name = tok[0];
      const bool name_ok = std::all_of(shot.name.begin(), shot.name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
      });
      if (!name_ok || shot.name[0] == '.') {
        problems += where + "shot name '" + shot.name + "': letters, digits, _ - . only (it names the golden file)\n";
        continue;
      }
      if (!names.insert(shot.name).second) {
        problems += where + "shot name '" + shot.name + "' is used twice\n";
        continue;
      }
      if (tok.size() < 2) {
        problems += where + "shot '" + shot.name + "' has no scene: NAME SCENE.json [key=value ...]\n";
        continue;
      }
      shot.scene = tok[1];
      first_option = 2;
    }
    bool ok = true;
    for (size_t i = first_option; i < tok.size() && ok; ++i) {
      const std::string e = applyOption(shot, tok[i]);
      if (!e.empty()) {
        problems += where + e + "\n";
        ok = false;
      }
    }
    if (!ok) continue;
    if (is_defaults) {
      defaults = shot;
      continue;
    }
    shot.scene_path = resolveScenePath(shot.scene, path);
    if (shot.scene_path.empty()) {
      problems += where + "scene " + shot.scene + " not found (relative to the working directory or to " + path + ")\n";
      continue;
    }
    try {
      const Scene scene = shotScene(shot);
      const unsigned have = sceneParts(scene);
      for (const std::string& s : shot.subject) {
        if (!(have & partBit(s)))
          problems += where + "subject=" + s + ": the scene " + shot.scene + " has no " + s + "\n";
      }
      if (!shot.wait.empty() && !scene.hopper) problems += where + "wait=" + shot.wait + ": the scene has no hopper\n";
      if (shot.check_subject && !shot.panel && have == 0)
        problems += where + "the scene " + shot.scene +
                    " has nothing to show (no head, chain or hopper); subject=none to allow\n";
    } catch (const InputError& e) {
      problems += where + "shot '" + shot.name + "': " + e.what() + "\n";
      continue;
    }
    list.shots.push_back(shot);
  }
  if (!problems.empty()) {
    problems.pop_back();
    throw InputError(problems);
  }
  if (list.shots.empty()) throw InputError(path + ": no shots (one per line: NAME SCENE.json [key=value ...])");
  return list;
}

ShotPicture renderShot(const Shot& shot) {
  const Scene scene = shotScene(shot);
  ShotPicture pic;
  pic.t = shot.t;
  if (shot.panel) {
    pic.image = renderPanelShot(scene, shot.t, &pic.renderer);
    return pic;
  }
  RenderSession session(scene);
  if (!session.simulateTo(shot.t)) {
    pic.problem = "the simulation stopped before t = " + std::to_string(shot.t) + " s: " + session.status();
    return pic;
  }
  if (!shot.wait.empty()) {
    pic.problem = waitFor(session.sim(), shot.wait);
    if (!pic.problem.empty()) return pic;
    pic.t = session.sim().time();
  }
  pic.image.width = session.width();
  pic.image.height = session.height();
  session.renderFrame(pic.t, pic.image.rgba);
  pic.renderer = session.glRenderer() + " / " + session.glVersion();

  if (shot.check_subject) {
    // Coverage: the share of pixels that change when a subject is left out (the same moment and
    // camera), counted strictly (no anti-aliasing excuse, a low threshold).
    DiffOptions strict;
    strict.threshold = 0.05;
    strict.detect_antialiasing = false;
    std::vector<std::pair<std::string, unsigned>> parts;
    for (const std::string& s : shot.subject) parts.emplace_back(s, partBit(s));
    if (parts.empty()) parts.emplace_back(partName(0), SceneDraw::parts(session.sim()));
    for (const auto& [name, bits] : parts) {
      Image without(pic.image.width, pic.image.height);
      session.renderFrame(pic.t, without.rgba, bits);
      pic.coverage.emplace_back(name, compareImages(pic.image, without, strict).share);
    }
  }
  return pic;
}

std::string subjectProblem(const Shot& shot, const ShotPicture& picture) {
  std::string out;
  char buf[256];
  for (const auto& [name, share] : picture.coverage) {
    if (share >= shot.min_subject) continue;
    std::snprintf(buf, sizeof buf, "%s%s covers %.3f%% of the picture, at least %.3f%% (min_subject=%g) needed",
                  out.empty() ? "" : "; ", name.c_str(), 100.0 * share, 100.0 * shot.min_subject, shot.min_subject);
    out += buf;
  }
  if (!out.empty()) out = "the subject is not in the picture: " + out + " (camera, ground or time wrong?)";
  return out;
}

Image composeComparison(const Image& expected, const Image& actual, const Image& diff) {
  const Image* parts[3] = {&expected, &actual, &diff};
  const int gap = 6;
  int w = gap, h = 0;
  for (const Image* p : parts) {
    const int pw = p->empty() ? std::max(expected.width, actual.width) : p->width;
    w += pw + gap;
    h = std::max(h, p->height);
  }
  Image out(w, h + 2 * gap, 40, 40, 44);
  int x0 = gap;
  for (const Image* p : parts) {
    for (int y = 0; y < p->height; ++y)
      std::memcpy(out.px(x0, y + gap), p->px(0, y), static_cast<size_t>(p->width) * 4);
    x0 += (p->empty() ? std::max(expected.width, actual.width) : p->width) + gap;
  }
  return out;
}

int runSnapshots(const ShotList& list, const SnapshotOptions& options, std::FILE* out, std::FILE* err) {
  if (options.update && options.ci) {
    std::fprintf(err,
                 "ponyhop snapshot: --update is refused under CI=true: goldens change only on purpose, "
                 "on a developer's machine, and are reviewed before they are committed\n");
    return 2;
  }
  for (const std::string& o : options.only) {
    if (std::none_of(list.shots.begin(), list.shots.end(), [&](const Shot& s) { return s.name == o; })) {
      std::fprintf(err, "ponyhop snapshot: --only %s: no such shot in %s\n", o.c_str(), list.path.c_str());
      return 2;
    }
  }
  int passed = 0, failed = 0, written = 0, broken = 0;
  std::string renderer;
  size_t name_w = 4;
  for (const Shot& s : list.shots) name_w = std::max(name_w, s.name.size());
  const int nw = static_cast<int>(name_w);
  std::error_code ec;

  for (const Shot& shot : list.shots) {
    if (!options.only.empty() && std::find(options.only.begin(), options.only.end(), shot.name) == options.only.end())
      continue;
    const std::string golden = (fs::path(list.golden_dir) / (shot.name + ".png")).string();
    ShotPicture pic;
    try {
      pic = renderShot(shot);
    } catch (const std::exception& e) {
      std::fprintf(out, "ERROR %-*s %s\n", nw, shot.name.c_str(), e.what());
      ++broken;
      continue;
    }
    if (!pic.problem.empty()) {
      std::fprintf(out, "FAIL  %-*s %s\n", nw, shot.name.c_str(), pic.problem.c_str());
      ++failed;
      continue;
    }
    renderer = pic.renderer;
    const std::string subject = subjectProblem(shot, pic);
    std::string cover;
    for (const auto& [name, share] : pic.coverage) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%s%s %.1f%%", cover.empty() ? "; subject " : ", ", name.c_str(), 100.0 * share);
      cover += buf;
    }
    const bool have_golden = fs::exists(golden, ec);

    if (options.update || !have_golden) {
      if (!have_golden && options.ci) {
        std::fprintf(out,
                     "FAIL  %-*s no golden %s (CI=true: goldens are never written in CI; run "
                     "`ponyhop snapshot %s` on your machine, look at the picture, commit it)\n",
                     nw, shot.name.c_str(), golden.c_str(), list.path.c_str());
        ++failed;
        continue;
      }
      if (!subject.empty()) {
        std::fprintf(out, "FAIL  %-*s golden NOT written: %s\n", nw, shot.name.c_str(), subject.c_str());
        ++failed;
        continue;
      }
      std::string e;
      fs::create_directories(list.golden_dir, ec);
      if (!savePng(golden, pic.image, &e)) {
        std::fprintf(err, "ponyhop snapshot: %s\n", e.c_str());
        ++broken;
        continue;
      }
      std::fprintf(out, "%s %-*s golden %s %s (%dx%d, t = %.4g s%s): look at it, then commit it\n",
                   have_golden ? "UPDATED" : "NEW  ", nw, shot.name.c_str(), golden.c_str(),
                   have_golden ? "rewritten" : "written (first run)", pic.image.width, pic.image.height, pic.t,
                   cover.c_str());
      ++written;
      continue;
    }

    std::string e;
    const Image expected = loadPng(golden, &e);
    if (expected.empty()) {
      std::fprintf(err, "ponyhop snapshot: golden %s\n", e.c_str());
      ++broken;
      continue;
    }
    Image diff;
    const DiffResult r = compareImages(expected, pic.image, shot.diff, &diff);
    if (r.pass && subject.empty()) {
      std::fprintf(out, "PASS  %-*s %.3f%% differ (allowed %.3f%%)%s\n", nw, shot.name.c_str(), 100.0 * r.share,
                   100.0 * shot.diff.max_diff_share, cover.c_str());
      ++passed;
      continue;
    }
    ++failed;
    fs::create_directories(options.out_dir, ec);
    const std::string actual_path = (fs::path(options.out_dir) / (shot.name + ".actual.png")).string();
    const std::string compare_path = (fs::path(options.out_dir) / (shot.name + ".compare.png")).string();
    std::string what;
    if (!r.same_size) {
      what = r.message;
    } else if (!r.pass) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "%.3f%% of the pixels differ (allowed %.3f%%), largest difference %.3f (threshold %g)",
                    100.0 * r.share, 100.0 * shot.diff.max_diff_share, r.max_delta, shot.diff.threshold);
      what = buf;
    }
    if (!subject.empty()) what += (what.empty() ? "" : "; ") + subject;
    const bool saved =
        savePng(actual_path, pic.image, &e) && savePng(compare_path, composeComparison(expected, pic.image, diff), &e);
    std::fprintf(out, "FAIL  %-*s %s\n", nw, shot.name.c_str(), what.c_str());
    std::string recorded;
    std::getline(std::ifstream((fs::path(list.golden_dir) / "RENDERER.txt").string()), recorded);
    if (!recorded.empty() && recorded != pic.renderer)
      std::fprintf(out, "      %-*s goldens made by %s; this run: %s\n", nw, "", recorded.c_str(),
                   pic.renderer.c_str());
    if (saved)
      std::fprintf(out, "      %-*s expected | actual | diff: %s (red: differs, yellow: anti-aliasing ignored)\n", nw,
                   "", compare_path.c_str());
    else
      std::fprintf(err, "ponyhop snapshot: %s\n", e.c_str()), ++broken;
  }

  if (written > 0 && !renderer.empty()) {
    const std::string rec = (fs::path(list.golden_dir) / "RENDERER.txt").string();
    if (!writeText(rec, renderer + "\n")) std::fprintf(err, "ponyhop snapshot: cannot write %s\n", rec.c_str());
  }
  std::fprintf(out, "%d passed, %d failed, %d golden%s written, %d error%s (goldens in %s, renderer %s)\n", passed,
               failed, written, written == 1 ? "" : "s", broken, broken == 1 ? "" : "s", list.golden_dir.c_str(),
               renderer.empty() ? "-" : renderer.c_str());
  if (broken > 0) return 2;
  return failed > 0 ? 1 : 0;
}

}  // namespace ponyhop

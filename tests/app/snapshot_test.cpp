// Golden frames and physics fingerprints: every demo scene rendered headless at chosen moments and
// compared with tests/snapshots/*.png through the perceptual comparator (engine/image_diff.h),
// and the full simulated state after N steps hashed and compared with a recorded value.
//
// Goldens are rewritten only on purpose: `make update-snapshots` (PONYHOP_UPDATE_SNAPSHOTS=1),
// which refuses to run in CI. A failure writes the actual frame and the diff image into the
// build tree and prints their paths and the figures.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/ui_headless.h"
#include "engine/asset_loader.h"
#include "engine/image.h"
#include "engine/image_diff.h"
#include "engine/render_session.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
const std::string kGoldenDir = "tests/snapshots";

bool updating() {
  const char* u = std::getenv("PONYHOP_UPDATE_SNAPSHOTS");
  return u && std::strcmp(u, "1") == 0;
}

bool inCi() {
  const char* ci = std::getenv("CI");
  return ci && *ci && std::strcmp(ci, "0") != 0 && std::strcmp(ci, "false") != 0;
}

std::string failDir() {
  const std::string d = std::string(PONYHOP_TEST_OUT) + "/snapshots";
  fs::create_directories(d);
  return d;
}

// One golden frame: a scene at a time, at a modest size.
struct Shot {
  const char* name;
  const char* scene;
  double t;  // s
  std::vector<std::string> sets;
  // Hopper shots: from t on, step to the first moment in stance at the bottom of the bounce (1) or
  // in flight just past the apex (0). -1: render at t.
  int contact = -1;
  bool panel = false;  // draw the tuning panel beside the scene (render --ui)
  // What the picture is of, as overrides that recolour one part each (chain.color=..., ...):
  // ShowsItsSubject asks that each recolouring changes enough of the picture.
  std::vector<std::string> subject = {};
};

std::ostream& operator<<(std::ostream& os, const Shot& s) { return os << s.name; }

Scene shotScene(const Shot& shot) {
  std::vector<Override> o;
  for (const auto& s : shot.sets) o.push_back(parseOverride(s));
  Scene scene = loadScene(shot.scene, o);
  scene.render.width = 320;
  scene.render.height = 180;
  scene.render.samples = 4;
  scene.light.shadow_size = 1024;
  return scene;
}

Image renderShot(const Scene& scene, double t, std::string* renderer = nullptr, int contact = -1) {
  RenderSession session(scene);
  EXPECT_TRUE(session.simulateTo(t)) << session.status();
  if (contact >= 0) {
    Sim& rt = session.sim();
    const Hopper* h = rt.hopper();
    EXPECT_TRUE(h != nullptr);
    auto reached = [&] {
      const double vz = h->centerOfMassVelocity(rt.world()).z();
      return contact == 1 ? h->inContact() && vz >= 0.0 : !h->inContact() && vz <= 0.0;
    };
    const double limit = t + 3.0;
    while (h && rt.ok() && rt.time() < limit && !reached()) rt.step();
    EXPECT_TRUE(h && reached()) << "no " << (contact ? "stance" : "flight") << " moment within 3 s of t = " << t;
    t = rt.time();
  }
  Image img;
  img.width = session.width();
  img.height = session.height();
  session.renderFrame(t, img.rgba);
  if (renderer) *renderer = session.glRenderer() + " / " + session.glVersion();
  return img;
}

class Snapshot : public ::testing::TestWithParam<Shot> {};

TEST_P(Snapshot, MatchesGolden) {
  const Shot& shot = GetParam();
  if (!fs::exists(shot.scene)) GTEST_SKIP() << shot.scene << " is not in this tree";
  std::string renderer;
  Image actual;
  if (shot.panel) {
    // The panel beside the scene, as `ponyhop render --ui` draws it.
    Scene scene = shotScene(shot);
    HeadlessUi ui(scene, 320, 360);
    ui.sim().readouts().show_wall_clock = false;  // measured times differ run to run
    UiInput in;
    ui.frame(in, nullptr, 0.0);  // lay the widgets out once
    actual.width = ui.width();
    actual.height = ui.height();
    ui.frame(in, &actual.rgba, shot.t);
    renderer = glRendererName() + " / " + glVersionString();
  } else {
    actual = renderShot(shotScene(shot), shot.t, &renderer, shot.contact);
  }
  const std::string golden = kGoldenDir + "/" + shot.name + ".png";

  if (updating()) {
    ASSERT_FALSE(inCi()) << "PONYHOP_UPDATE_SNAPSHOTS is refused in CI: goldens change only on purpose";
    fs::create_directories(kGoldenDir);
    std::string err;
    ASSERT_TRUE(savePng(golden, actual, &err)) << err;
    std::ofstream(kGoldenDir + "/RENDERER.txt") << renderer << "\n";
    std::printf("updated %s\n", golden.c_str());
    return;
  }
  ASSERT_TRUE(fs::exists(golden)) << golden << " is missing: run `make update-snapshots` and commit it";
  const Image expected = loadPng(golden);
  Image diff;
  DiffOptions options;
  // The panel shows live timings (physics us/step, frame ms) whose digits differ run to run:
  // allow 0.5 % there (a few numbers' worth of glyphs); layout and parameter changes exceed it.
  if (shot.panel) options.max_diff_share = 0.005;
  const DiffResult r = compareImages(expected, actual, options, &diff);
  if (!r.pass) {
    const std::string a = failDir() + "/" + shot.name + ".actual.png";
    const std::string d = failDir() + "/" + shot.name + ".diff.png";
    std::string err;
    savePng(a, actual, &err);
    if (!diff.rgba.empty()) savePng(d, diff, &err);
    std::ifstream rec(kGoldenDir + "/RENDERER.txt");
    std::string recorded;
    std::getline(rec, recorded);
    ADD_FAILURE() << shot.name << ": " << r.differing << " pixels differ (" << 100.0 * r.share << " %, allowed "
                  << 100.0 * options.max_diff_share << " %), largest difference " << r.max_delta << ", "
                  << r.antialiased << " anti-aliased pixels ignored\n"
                  << "  expected: " << golden << "\n  actual:   " << a << "\n  diff:     " << d
                  << "\n  goldens made by: " << recorded << "\n  this run:        " << renderer
                  << "\n  (if the change is intended: make update-snapshots, review, commit)";
  }
}

const char* const kHeadRecolor = "head.materials=color,head.color=[0,1,0]";
const char* const kChainRecolor = "chain.color=[1,0,1]";
const char* const kHopperRecolor = "hopper.body_color=[0,0,1],hopper.leg_color=[0,0,1],hopper.foot_color=[0,0,1]";

const Shot kShots[] = {
    {"head", "assets/scenes/head.json", 0.8, {}, -1, false, {kHeadRecolor}},
    {"ponytail_rest", "assets/scenes/ponytail.json", 0.0, {}, -1, false, {kHeadRecolor, kChainRecolor}},
    {"ponytail_swing", "assets/scenes/ponytail.json", 2.7, {}, -1, false, {kHeadRecolor, kChainRecolor}},
    {"chain_swing", "assets/scenes/chain.json", 0.45, {}, -1, false, {kChainRecolor}},
    {"hopper_flight", "assets/scenes/hopper.json", 2.0, {}, 0, false, {kHopperRecolor}},
    {"hopper_stance", "assets/scenes/hopper.json", 2.0, {}, 1, false, {kHopperRecolor}},
    {"ponytail_hopper", "assets/scenes/ponytail_hopper.json", 2.5, {}, -1, false, {kChainRecolor, kHopperRecolor}},
    {"panel", "assets/scenes/ponytail.json", 1.0, {}, -1, true},
};

// Every golden shows its subject: recolouring each part it is of (the same moment and camera)
// changes at least 0.2 % of the picture. A golden of an empty floor (the chain drawn under a
// ground at the wrong height, a camera looking away) fails here.
TEST_P(Snapshot, ShowsItsSubject) {
  const Shot& shot = GetParam();
  if (shot.panel) GTEST_SKIP() << shot.name << ": the panel shot's subject is the panel";
  ASSERT_FALSE(shot.subject.empty()) << shot.name << ": name what the golden is of";
  if (!fs::exists(shot.scene)) GTEST_SKIP() << shot.scene << " is not in this tree";
  const Image plain = renderShot(shotScene(shot), shot.t, nullptr, shot.contact);
  DiffOptions strict;  // every changed pixel counts
  strict.threshold = 0.05;
  strict.detect_antialiasing = false;
  for (const std::string& recolor : shot.subject) {
    Shot other = shot;
    std::string rest = recolor;
    while (!rest.empty()) {  // "a=1,b=[0,1,0]": split at commas outside brackets
      int depth = 0;
      size_t i = 0;
      for (; i < rest.size(); ++i) {
        if (rest[i] == '[') ++depth;
        if (rest[i] == ']') --depth;
        if (rest[i] == ',' && depth == 0) break;
      }
      other.sets.push_back(rest.substr(0, i));
      rest = i < rest.size() ? rest.substr(i + 1) : "";
    }
    const Image recolored = renderShot(shotScene(other), shot.t, nullptr, shot.contact);
    const double share = compareImages(plain, recolored, strict).share;
    std::printf("%s: %s changes %.2f %% of the picture\n", shot.name, recolor.c_str(), 100.0 * share);
    EXPECT_GE(share, 0.002) << shot.name << ": " << recolor << " changes only " << 100.0 * share
                            << " % of the picture: its subject is not in it (camera, ground or time wrong?)";
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, Snapshot, ::testing::ValuesIn(kShots),
                         [](const ::testing::TestParamInfo<Shot>& i) { return std::string(i.param.name); });

// ---------------------------------------------------------------------------------------------
// Physics fingerprints: a hash of every body's full state (bits of x, q, v, w) after N steps.

uint64_t fnv1a(uint64_t h, const void* data, size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

std::string stateHash(const World& world) {
  uint64_t h = 1469598103934665603ull;
  for (const RigidBody& b : world.bodies()) {
    const double v[13] = {b.x.x(), b.x.y(), b.x.z(), b.q.w(), b.q.x(), b.q.y(), b.q.z(),
                          b.v.x(), b.v.y(), b.v.z(), b.w.x(), b.w.y(), b.w.z()};
    h = fnv1a(h, v, sizeof(v));
  }
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string fingerprint(const std::string& scene_path, int steps) {
  Sim rt(loadScene(scene_path), &assimpAssets());
  for (int i = 0; i < steps && rt.ok(); ++i) rt.step();
  EXPECT_TRUE(rt.ok()) << rt.status();
  return stateHash(rt.world());
}

struct Print {
  const char* scene;
  int steps;
};
std::ostream& operator<<(std::ostream& os, const Print& p) { return os << p.scene; }

class Fingerprint : public ::testing::TestWithParam<Print> {};

TEST_P(Fingerprint, MatchesRecorded) {
  const Print& p = GetParam();
  if (!fs::exists(p.scene)) GTEST_SKIP() << p.scene << " is not in this tree";
  const std::string file = kGoldenDir + "/fingerprints.json";
  nlohmann::json recorded = nlohmann::json::object();
  if (fs::exists(file)) recorded = nlohmann::json::parse(std::ifstream(file));
  const std::string key = std::string(p.scene) + "@" + std::to_string(p.steps);
  const std::string h = fingerprint(p.scene, p.steps);
  if (updating()) {
    ASSERT_FALSE(inCi()) << "PONYHOP_UPDATE_SNAPSHOTS is refused in CI";
    recorded[key] = h;
    std::ofstream(file + ".tmp") << recorded.dump(2) << "\n";
    fs::rename(file + ".tmp", file);
    return;
  }
  ASSERT_TRUE(recorded.contains(key)) << key << " has no recorded fingerprint: run `make update-snapshots`";
  EXPECT_EQ(recorded[key].get<std::string>(), h)
      << p.scene << ": the state after " << p.steps
      << " steps changed. If the physics change is intended: make update-snapshots, review, commit.";
}

const Print kPrints[] = {
    {"assets/scenes/chain.json", 600},
    {"assets/scenes/ponytail.json", 600},
    {"assets/scenes/hopper.json", 2000},
    {"assets/scenes/ponytail_hopper.json", 2000},
};

INSTANTIATE_TEST_SUITE_P(Scenes, Fingerprint, ::testing::ValuesIn(kPrints),
                         [](const ::testing::TestParamInfo<Print>& i) {
                           std::string n = fs::path(i.param.scene).stem().string();
                           return n;
                         });

// The fingerprint sees a change the pictures could hide: one more step, or a nudge of 1e-12 m.
TEST(FingerprintHash, DetectsTinyPhysicsChanges) {
  const std::string a = fingerprint("assets/scenes/chain.json", 200);
  EXPECT_EQ(a, fingerprint("assets/scenes/chain.json", 200)) << "not deterministic";
  EXPECT_NE(a, fingerprint("assets/scenes/chain.json", 201));
  Sim rt(loadScene("assets/scenes/chain.json"), &assimpAssets());
  rt.world().body(rt.chain()->links.back()).x.x() += 1e-12;
  for (int i = 0; i < 200; ++i) rt.step();
  EXPECT_NE(a, stateHash(rt.world()));
}

}  // namespace
}  // namespace ponyhop

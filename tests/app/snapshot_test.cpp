// Golden frames and physics fingerprints: every demo scene rendered headless at chosen moments and
// compared with tests/snapshots/*.png through the perceptual comparator (engine/image_diff.h),
// and the full simulated state after N steps hashed and compared with a recorded value.
//
// The shots are listed in tests/snapshots/shots.txt and run through `ponyhop snapshot`'s code
// (app/snapshot.h). Goldens and fingerprints are rewritten only on purpose: `make update-snapshots`
// (`ponyhop snapshot --update`, PONYHOP_UPDATE_SNAPSHOTS=1 for the fingerprints), refused in CI.
// A failure writes the actual frame and the expected | actual | diff picture into the build tree.
#include "app/snapshot.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/asset_loader.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
const std::string kGoldenDir = "tests/snapshots";

bool updating() {
  const char* u = std::getenv("PONYHOP_UPDATE_SNAPSHOTS");
  return u && std::strcmp(u, "1") == 0;
}

std::string failDir() {
  const std::string d = std::string(PONYHOP_TEST_OUT) + "/snapshots";
  fs::create_directories(d);
  return d;
}

// The shot list of the project's goldens: the same file `ponyhop snapshot` reads.
const char* const kShotList = "tests/snapshots/shots.txt";

std::vector<Shot> projectShots() {
  try {
    return loadShotList(kShotList).shots;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return {};  // ShotList.Loads says why
  }
}

TEST(ShotList, Loads) {
  const ShotList list = loadShotList(kShotList);  // throws with the file, line and key
  EXPECT_GE(list.shots.size(), 8u);
  EXPECT_EQ(list.golden_dir, kGoldenDir);
}

}  // namespace

// gtest names a shot by its name and line instead of dumping its bytes.
void PrintTo(const Shot& s, std::ostream* os) { *os << s.name << " (shots.txt:" << s.line << ")"; }

namespace {

class Snapshot : public ::testing::TestWithParam<Shot> {};

// Each golden through the command's own code (app/snapshot.h), as CI would run it: a missing
// golden fails and is never written here.
TEST_P(Snapshot, MatchesGolden) {
  const Shot& shot = GetParam();
  ShotList one;
  one.path = kShotList;
  one.golden_dir = kGoldenDir;
  one.shots = {shot};
  SnapshotOptions options;
  options.ci = true;
  options.out_dir = failDir();
  EXPECT_EQ(runSnapshots(one, options, stdout, stderr), 0)
      << shot.name << ": see the lines above; the expected | actual | diff picture is in " << options.out_dir
      << " (if the change is intended: make update-snapshots, look at each golden, commit)";
}

// Every golden shows its subject: drawing the chain / the hopper / the head changes at least a
// share of the picture (min_subject, 0.2 % unless the list says otherwise). A golden of an empty
// floor fails here before it could be recorded.
TEST_P(Snapshot, ShowsItsSubject) {
  const Shot& shot = GetParam();
  if (shot.panel) GTEST_SKIP() << shot.name << ": the panel shot's subject is the panel";
  ASSERT_TRUE(shot.check_subject) << shot.name << ": every project golden names its subject";
  ASSERT_FALSE(shot.subject.empty()) << shot.name << ": name the subject (subject=chain...) in " << kShotList;
  const ShotPicture pic = renderShot(shot);
  ASSERT_TRUE(pic.problem.empty()) << pic.problem;
  ASSERT_EQ(pic.coverage.size(), shot.subject.size());
  for (const auto& [name, share] : pic.coverage) {
    EXPECT_GE(share, shot.min_subject) << shot.name << ": " << name << " covers " << 100.0 * share
                                       << " % of the picture";
    std::printf("%s: %s covers %.2f %% of the picture\n", shot.name.c_str(), name.c_str(), 100.0 * share);
  }
}

INSTANTIATE_TEST_SUITE_P(Shots, Snapshot, ::testing::ValuesIn(projectShots()),
                         [](const ::testing::TestParamInfo<Shot>& i) { return i.param.name; });

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
  Sim sim(loadScene(scene_path), &assimpAssets());
  for (int i = 0; i < steps && sim.ok(); ++i) sim.step();
  EXPECT_TRUE(sim.ok()) << sim.status();
  return stateHash(sim.world());
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
    {"assets/scenes/chain.json", 600},    {"assets/scenes/ponytail.json", 600},
    {"assets/scenes/hopper.json", 2000},  {"assets/scenes/ponytail_hopper.json", 2000},
    {"assets/scenes/pigtails.json", 240},
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
  Sim sim(loadScene("assets/scenes/chain.json"), &assimpAssets());
  sim.world().body(sim.chain()->links.back()).x.x() += 1e-12;
  for (int i = 0; i < 200; ++i) sim.step();
  EXPECT_NE(a, stateHash(sim.world()));
}

}  // namespace
}  // namespace ponyhop

// Keyframes imported through assimp (engine/animation_import.h): a small animated glTF written
// here (position and rotation keyed at different times), and the committed
// assets/head/head_animated.gltf (a 2 s nod).
#include "engine/animation_import.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>

using namespace ponyhop;
using Eigen::AngleAxisd;
using Eigen::Quaterniond;
using Eigen::Vector3d;

namespace {

constexpr double kPi = std::numbers::pi;
double deg(double d) { return d * kPi / 180.0; }

// A glTF 2.0 file (+ .bin) with one triangle on node "box" and, when `animated`, an animation
// "wiggle": rotation about +y (glTF up) of 0, 20, 0, -20, 0 deg at 0, 0.5, 1, 1.5, 2 s and
// translation (0,0,0), (0.1, 0.2, 0.3), (0,0,0) m at 0, 1, 2 s.
std::string writeTinyGltf(const std::string& name, bool animated) {
  // One folder per test: ctest runs the tests of this file as parallel processes, and two of them
  // writing the same wiggle.bin raced (one read it while another rewrote it).
  const std::filesystem::path dir = std::filesystem::path(PONYHOP_TEST_OUT) / "animation_import" /
                                    ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::filesystem::create_directories(dir);
  std::vector<float> data{0, 0, 0, 1, 0, 0, 0, 1, 0};  // positions (36 bytes)
  const float sim[5] = {0, 0.5f, 1, 1.5f, 2};
  const float ra[5] = {0, 20, 0, -20, 0};
  const float tt[3] = {0, 1, 2};
  data.insert(data.end(), sim, sim + 5);  // offset 36, 20 bytes
  for (float a : ra) {                    // offset 56, 80 bytes: xyzw about +y
    const float h = static_cast<float>(deg(a) / 2);
    data.insert(data.end(), {0.0f, std::sin(h), 0.0f, std::cos(h)});
  }
  data.insert(data.end(), tt, tt + 3);                            // offset 136, 12 bytes
  data.insert(data.end(), {0, 0, 0, 0.1f, 0.2f, 0.3f, 0, 0, 0});  // offset 148, 36 bytes
  const std::string bin = name + ".bin";
  std::ofstream(dir / bin, std::ios::binary)
      .write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size() * 4));
  std::string anim;
  if (animated) {
    anim = R"(,
  "animations": [{"name": "wiggle",
    "samplers": [{"input": 1, "output": 2, "interpolation": "LINEAR"}, {"input": 3, "output": 4, "interpolation": "LINEAR"}],
    "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}},
                 {"sampler": 1, "target": {"node": 0, "path": "translation"}}]}])";
  }
  const std::string gltf = R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [{"name": "box", "mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "buffers": [{"uri": ")" + bin +
                           R"(", "byteLength": 184}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 20},
                  {"buffer": 0, "byteOffset": 56, "byteLength": 80}, {"buffer": 0, "byteOffset": 136, "byteLength": 12},
                  {"buffer": 0, "byteOffset": 148, "byteLength": 36}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5126, "count": 5, "type": "SCALAR", "min": [0], "max": [2]},
    {"bufferView": 2, "componentType": 5126, "count": 5, "type": "VEC4"},
    {"bufferView": 3, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0], "max": [2]},
    {"bufferView": 4, "componentType": 5126, "count": 3, "type": "VEC3"}
  ])" + anim + "\n}\n";
  const std::filesystem::path path = dir / (name + ".gltf");
  std::ofstream(path) << gltf;
  return path.string();
}

}  // namespace

TEST(AnimationImport, MergesChannelsOntoTheUnionOfKeyTimes) {
  const std::string path = writeTinyGltf("wiggle", true);
  std::string err;
  const auto a = importAnimation(path, {}, &err);
  ASSERT_TRUE(a) << err;
  EXPECT_EQ(a->animation_name, "wiggle");
  EXPECT_EQ(a->node_name, "box");
  EXPECT_EQ(a->rotation_keys, 5);
  EXPECT_EQ(a->position_keys, 3);
  ASSERT_EQ(a->samples.size(), 5u);  // {0, 1, 2} u {0, 0.5, 1, 1.5, 2}
  const double angles[5] = {0, 20, 0, -20, 0};
  for (int i = 0; i < 5; ++i) {
    const PoseSample& s = a->samples[i];
    EXPECT_NEAR(s.t, 0.5 * i, 1e-6) << "ticks -> seconds";
    const Quaterniond want(AngleAxisd(deg(angles[i]), Vector3d::UnitY()));
    EXPECT_LE(s.rotation.angularDistance(want), 1e-6) << i;
    // Position keyed at 0, 1, 2 s only: linear in between (0.5 s: half of (0.1, 0.2, 0.3)).
    const double u = i <= 2 ? 0.5 * i : 0.5 * (4 - i);
    EXPECT_LE((s.position - u * Vector3d(0.1, 0.2, 0.3)).norm(), 1e-6) << i;
  }
}

TEST(AnimationImport, ConvertsYUpToZUp) {
  const std::string path = writeTinyGltf("wiggle", true);
  std::string err;
  AnimationImportOptions opt;
  opt.y_up_to_z_up = true;
  const auto a = importAnimation(path, opt, &err);
  ASSERT_TRUE(a) << err;
  ASSERT_EQ(a->samples.size(), 5u);
  // At 0.5 s: the file's 20 deg about +y (up) is 20 deg about world +z (up); (0.05, 0.1, 0.15) ->
  // (x, -z, y) = (0.05, -0.15, 0.1).
  EXPECT_LE(a->samples[1].rotation.angularDistance(Quaterniond(AngleAxisd(deg(20), Vector3d::UnitZ()))), 1e-6);
  EXPECT_LE((a->samples[1].position - Vector3d(0.05, -0.15, 0.1)).norm(), 1e-6);
  EXPECT_LE((a->samples[2].position - Vector3d(0.1, -0.3, 0.2)).norm(), 1e-6);
}

TEST(AnimationImport, ClearErrorsNameTheFile) {
  std::string err;
  const std::string still = writeTinyGltf("still", false);
  EXPECT_FALSE(importAnimation(still, {}, &err));
  EXPECT_NE(err.find(still), std::string::npos) << err;
  EXPECT_NE(err.find("no animation"), std::string::npos) << err;

  EXPECT_FALSE(importAnimation("assets/head/does_not_exist.gltf", {}, &err));
  EXPECT_NE(err.find("does_not_exist.gltf"), std::string::npos) << err;

  const std::string path = writeTinyGltf("wiggle", true);
  AnimationImportOptions opt;
  opt.node = "tail";
  EXPECT_FALSE(importAnimation(path, opt, &err));
  EXPECT_NE(err.find("\"tail\""), std::string::npos) << err;
  EXPECT_NE(err.find("\"box\""), std::string::npos) << err;
  opt = {};
  opt.animation = "dance";
  EXPECT_FALSE(importAnimation(path, opt, &err));
  EXPECT_NE(err.find("\"wiggle\""), std::string::npos) << err;
}

TEST(AnimationImport, TrackThroughImportedSamplesIsSmooth) {
  const std::string path = writeTinyGltf("wiggle", true);
  std::string err;
  AnimationImportOptions opt;
  opt.y_up_to_z_up = true;
  const auto tr = importAnimationTrack(path, opt, {LoopMode::Loop, 1.0, 1.0}, &err);
  ASSERT_TRUE(tr) << err;
  EXPECT_NEAR(tr->period(), 2.0, 1e-6);  // the last sample equals the first: it closes the loop
  const auto a = importAnimation(path, opt, &err);
  for (const PoseSample& s : a->samples) {
    const KinematicState st = tr->evaluate(s.t);
    EXPECT_LE((st.x - s.position).norm(), 1e-9);
    EXPECT_LE(st.q.angularDistance(s.rotation), 1e-9);
  }
  // Acceleration continuous at the samples (C2, not the C1 of the file's linear keys).
  for (const PoseSample& s : a->samples) {
    const KinematicState l = tr->evaluate(s.t - 1e-7), r = tr->evaluate(s.t + 1e-7);
    EXPECT_LE((l.a - r.a).norm(), 1e-4 * (1 + l.a.norm())) << s.t;
    EXPECT_LE((l.alpha - r.alpha).norm(), 1e-4 * (1 + l.alpha.norm())) << s.t;
  }
}

// The head's own animation (assets/head/README.md): a 2 s nod, 9 keys every 0.25 s, rotation
// 15 deg * sin(pi t) about +x, translation (0, -2 mm sin^2(pi t), 5 mm sin(pi t)) in glTF
// coordinates; in the z-up world the bob becomes (0, -5 mm sin(pi t), -2 mm sin^2(pi t)).
TEST(AnimationImport, CommittedHeadNod) {
  const std::string path = "assets/head/head_animated.gltf";
  ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing";
  std::string err;
  AnimationImportOptions opt;
  opt.y_up_to_z_up = true;
  const auto a = importAnimation(path, opt, &err);
  ASSERT_TRUE(a) << err;
  EXPECT_EQ(a->node_name, "head");
  ASSERT_EQ(a->samples.size(), 9u);
  for (const PoseSample& s : a->samples) {
    const double sn = std::sin(kPi * s.t);
    EXPECT_LE(s.rotation.angularDistance(Quaterniond(AngleAxisd(deg(15) * sn, Vector3d::UnitX()))), 1e-5) << s.t;
    EXPECT_LE((s.position - Vector3d(0, -0.005 * sn, -0.002 * sn * sn)).norm(), 1e-6) << s.t;
  }
  EXPECT_NEAR(a->samples.front().t, 0.0, 1e-9);
  EXPECT_NEAR(a->samples.back().t, 2.0, 1e-6);
  // Played as a loop through the C2 track: nods down first (face, -y in the body, tips toward -z).
  KeyframeTrack tr;
  const Status s = KeyframeTrack::fromSamples(a->samples, {LoopMode::Loop, 1.0, 1.0}, tr);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_NEAR(tr.period(), 2.0, 1e-6);
  EXPECT_LT((tr.evaluate(0.5).q * Vector3d(0, -1, 0)).z(), -0.2);
  EXPECT_GT(tr.evaluate(0.25).w.x(), 0.1);
}

// Scene files: every field through reflect(), errors that name the file, the key and the range.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sim/scene_io.h"

namespace ponyhop {
namespace {

using nlohmann::json;

std::string errorOf(const json& j, const std::vector<Override>& o = {}) {
  try {
    parseScene(j, "test.json", o);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

TEST(SceneIo, DefaultsWhenEmpty) {
  const Scene s = parseScene(json::object(), "test.json");
  EXPECT_DOUBLE_EQ(s.physics.dt, PhysicsParams{}.dt);
  EXPECT_FALSE(s.head.has_value());
  EXPECT_FALSE(s.chain.has_value());
}

TEST(SceneIo, ReadsNestedSectionsAndEnums) {
  const json j = json::parse(R"({
    "physics": {"dt": 0.002, "integrator": "symplectic_euler", "gravity": [0, 0, -3]},
    "anchor": {"motion": "shake"},
    "chain": {"links": 12, "attach": "anchor"}
  })");
  const Scene s = parseScene(j, "test.json");
  EXPECT_DOUBLE_EQ(s.physics.dt, 0.002);
  EXPECT_EQ(s.physics.integrator, Integrator::SymplecticEuler);
  EXPECT_DOUBLE_EQ(s.physics.gravity.z(), -3.0);
  ASSERT_TRUE(s.chain.has_value());
  EXPECT_EQ(s.chain->links, 12);
  ASSERT_TRUE(s.anchor.has_value());
  EXPECT_EQ(s.anchor->motion, AnchorMotion::Shake);
}

TEST(SceneIo, UnknownKeyNamesKeyAndAllowed) {
  const std::string e = errorOf(json::parse(R"({"physics": {"dtt": 0.01}})"));
  EXPECT_NE(e.find("test.json"), std::string::npos) << e;
  EXPECT_NE(e.find("physics.dtt: unknown key"), std::string::npos) << e;
  EXPECT_NE(e.find("dt"), std::string::npos) << e;
}

TEST(SceneIo, WrongTypeAndRange) {
  EXPECT_NE(errorOf(json::parse(R"({"physics": {"dt": "fast"}})")).find("physics.dt: must be a number"),
            std::string::npos);
  const std::string e = errorOf(json::parse(R"({"physics": {"dt": -1}})"));
  EXPECT_NE(e.find("physics.dt"), std::string::npos) << e;
  EXPECT_NE(e.find("[1e-06, 0.1] s"), std::string::npos) << e;
  EXPECT_NE(errorOf(json::parse(R"({"anchor": {}, "chain": {"links": 0}})")).find("chain.links"),
            std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"anchor": {}, "chain": {"links": 2.5}})")).find("whole number"),
            std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"physics": {"integrator": "leapfrog"}})")).find("\"rk4\""),
            std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"physics": {"gravity": [0, 0]}})")).find("3 numbers"),
            std::string::npos);
}

TEST(SceneIo, EveryProblemIsListed) {
  const std::string e = errorOf(json::parse(R"({"physics": {"dt": 0, "substeps": -1}, "bogus": 1})"));
  EXPECT_NE(e.find("3 problems"), std::string::npos) << e;
}

TEST(SceneIo, OverridesApplyAndAreValidated) {
  const json j = json::parse(R"({"anchor": {}, "chain": {"links": 8}})");
  const Scene s = parseScene(j, "t.json", {parseOverride("chain.links=32"), parseOverride("physics.dt=0.001"),
                                           parseOverride("physics.integrator=rk4")});
  EXPECT_EQ(s.chain->links, 32);
  EXPECT_DOUBLE_EQ(s.physics.dt, 0.001);
  const std::string e = errorOf(j, {parseOverride("physics.dt=nan")});
  EXPECT_NE(e.find("--set physics.dt=nan"), std::string::npos) << e;
  EXPECT_NE(errorOf(j, {parseOverride("physics.dtx=1")}).find("unknown key"), std::string::npos);
  EXPECT_THROW(parseOverride("novalue"), SceneError);
}

TEST(SceneIo, OverrideCannotConjureAMissingSection) {
  const std::string e = errorOf(json::parse(R"({"anchor": {}, "chain": {}})"), {parseOverride("head.scale=2")});
  EXPECT_NE(e.find("no 'head' section"), std::string::npos) << e;
}

TEST(SceneIo, CrossFieldRules) {
  EXPECT_NE(errorOf(json::parse(R"({"chain": {"attach": "head"}})")).find("needs a head"), std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"head": {"mesh": "no/such/file.obj"}})")).find("head.mesh: file not found"),
            std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"render": {"width": 641}})")).find("even"), std::string::npos);
}

TEST(SceneIo, RoundTripIsExact) {
  Scene s;
  s.physics.dt = 1.0 / 480.0;
  s.physics.gravity = {0.1, -0.2, -9.80665};
  s.anchor.emplace();
  s.chain.emplace();
  s.chain->links = 17;
  s.chain->damping = 0.1 / 3.0;
  s.camera.fov = 33.333333333333336;
  const json j = sceneToJson(s);
  const Scene t = parseScene(j, "roundtrip");
  EXPECT_EQ(sceneToJson(t), j);
  EXPECT_EQ(t.physics.dt, s.physics.dt);  // exact: the file keeps every bit
  EXPECT_EQ(t.chain->damping, s.chain->damping);
}

TEST(SceneIo, SaveIsAtomicAndLoadable) {
  std::filesystem::create_directories(PONYHOP_TEST_OUT);
  const std::string path = std::string(PONYHOP_TEST_OUT) + "/saved_scene.json";
  Scene s;
  s.anchor.emplace();
  s.chain.emplace();
  s.chain->links = 5;
  saveScene(s, path);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  EXPECT_EQ(loadScene(path).chain->links, 5);
}

TEST(SceneIo, MissingAndBrokenFiles) {
  try {
    loadScene("no/such/scene.json");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("no/such/scene.json"), std::string::npos);
  }
  std::filesystem::create_directories(PONYHOP_TEST_OUT);
  const std::string path = std::string(PONYHOP_TEST_OUT) + "/broken.json";
  std::ofstream(path) << "{ \"physics\": { \"dt\": 0.01, } ";
  try {
    loadScene(path);
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
  }
}

TEST(SceneIo, ReferenceListsEveryField) {
  const std::string md = sceneReferenceMarkdown();
  EXPECT_NE(md.find("`physics.dt`"), std::string::npos);
  EXPECT_NE(md.find("`chain.links`"), std::string::npos);
  EXPECT_NE(md.find("`head.animation.keys.N.t`"), std::string::npos);
}

}  // namespace
}  // namespace ponyhop

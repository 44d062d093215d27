// Scene files: every field through reflect(), errors that name the file, the key and the range.
#include "sim/scene_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

namespace ponyhop {
namespace {

using nlohmann::json;

std::string errorOf(const json& j, const std::vector<Override>& o = {}) {
  try {
    parseScene(j, "test.json", o);
  } catch (const InputError& e) {
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

TEST(SceneIo, HoppersListIsReadAndEachEntryChecked) {
  const Scene s =
      parseScene(json::parse(R"({"hopper": {}, "hoppers": [{"position": [1, 0, 1.05]}, {"position": [2, 0, 1.1]}]})"),
                 "test.json", {});
  ASSERT_EQ(s.hoppers.size(), 2u);
  EXPECT_DOUBLE_EQ(s.hoppers[1].position.x(), 2.0);
  const std::string e = errorOf(json::parse(R"({"hoppers": [{}, {"min_length": 0.85}]})"));
  EXPECT_NE(e.find("hoppers.1"), std::string::npos) << e;
  EXPECT_NE(e.find("min_length"), std::string::npos) << e;
  const std::string range = errorOf(json::parse(R"({"hoppers": [{"friction": -1}]})"));
  EXPECT_NE(range.find("hoppers.0.friction"), std::string::npos) << range;
}

TEST(SceneIo, ChainsListIsReadAndEachEntryChecked) {
  const Scene s = parseScene(json::parse(R"({"anchor": {}, "chain": {},
      "chains": [{"links": 3, "anchor": [0.05, 0.1, 0]}, {"links": 4, "color": [1, 0, 0]}]})"),
                             "test.json", {{"chains.1.links", "5"}});
  ASSERT_EQ(chainCount(s), 3u);
  EXPECT_EQ(chainSection(s, 1).links, 3);
  EXPECT_EQ(chainSection(s, 2).links, 5) << "--set reaches a listed chain";
  EXPECT_DOUBLE_EQ(s.chains[0].anchor.x(), 0.05);
  EXPECT_EQ(chainKey(s, 2), "chains.1");
  const std::string range = errorOf(json::parse(R"({"anchor": {}, "chains": [{}, {"taper": 2}]})"));
  EXPECT_NE(range.find("chains.1.taper"), std::string::npos) << range;
  const std::string head = errorOf(json::parse(R"({"anchor": {}, "chains": [{"attach": "head"}]})"));
  EXPECT_NE(head.find("chains.0.attach: \"head\" needs a head section"), std::string::npos) << head;
  const std::string hopper =
      errorOf(json::parse(R"({"hopper": {}, "chains": [{"attach": "hopper"}, {"attach": "hopper", "hopper": 1}]})"));
  EXPECT_NE(hopper.find("chains.1.hopper: 1 is not a hopper of this scene (it has 1"), std::string::npos) << hopper;
  EXPECT_EQ(hopper.find("chains.0"), std::string::npos) << hopper;
  const std::string zero = errorOf(json::parse(R"({"anchor": {}, "chains": [{"direction": [0, 0, 0]}]})"));
  EXPECT_NE(zero.find("chains.0.direction: must not be the zero vector"), std::string::npos) << zero;
}

TEST(SceneIo, UnknownKeyNamesKeyAndAllowed) {
  const std::string e = errorOf(json::parse(R"({"physics": {"dtt": 0.01}})"));
  EXPECT_NE(e.find("test.json"), std::string::npos) << e;
  EXPECT_NE(e.find("physics.dtt: unknown key"), std::string::npos) << e;
  EXPECT_NE(e.find("dt"), std::string::npos) << e;
}

TEST(SceneIo, WrongTypeAndRange) {
  EXPECT_NE(errorOf(json::parse(R"({"head": {"scalp_hair": "yes"}})")).find("head.scalp_hair: must be"),
            std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"physics": {"dt": "fast"}})")).find("physics.dt: must be a number"),
            std::string::npos);
  const std::string e = errorOf(json::parse(R"({"physics": {"dt": -1}})"));
  EXPECT_NE(e.find("physics.dt"), std::string::npos) << e;
  EXPECT_NE(e.find("[1e-06, 0.1] s"), std::string::npos) << e;
  EXPECT_NE(errorOf(json::parse(R"({"anchor": {}, "chain": {"links": 0}})")).find("chain.links"), std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"anchor": {}, "chain": {"links": 2.5}})")).find("whole number"), std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"physics": {"integrator": "leapfrog"}})")).find("\"rk4\""), std::string::npos);
  EXPECT_NE(errorOf(json::parse(R"({"physics": {"gravity": [0, 0]}})")).find("3 numbers"), std::string::npos);
  // head.box_min/box_max: a box with volume, or equal corners (found from the mesh).
  const std::string box = errorOf(json::parse(R"({"head": {"box_min": [1, 1, 1], "box_max": [0, 2, 2]}})"));
  EXPECT_NE(box.find("head.box_max: must exceed head.box_min on every axis"), std::string::npos) << box;
  EXPECT_NE(errorOf(json::parse(R"({"head": {"box_min": [0, "a", 0]}})")).find("head.box_min"), std::string::npos);
}

TEST(SceneIo, EveryProblemIsListed) {
  const std::string e = errorOf(json::parse(R"({"physics": {"dt": 0, "substeps": -1}, "bogus": 1})"));
  EXPECT_NE(e.find("3 problems"), std::string::npos) << e;
}

TEST(SceneIo, OverridesApplyAndAreValidated) {
  const json j = json::parse(R"({"anchor": {}, "chain": {"links": 8}})");
  const Scene s = parseScene(
      j, "t.json",
      {parseOverride("chain.links=32"), parseOverride("physics.dt=0.001"), parseOverride("physics.integrator=rk4")});
  EXPECT_EQ(s.chain->links, 32);
  EXPECT_DOUBLE_EQ(s.physics.dt, 0.001);
  const std::string e = errorOf(j, {parseOverride("physics.dt=nan")});
  EXPECT_NE(e.find("--set physics.dt=nan"), std::string::npos) << e;
  EXPECT_NE(errorOf(j, {parseOverride("physics.dtx=1")}).find("unknown key"), std::string::npos);
  EXPECT_THROW(parseOverride("novalue"), InputError);
}

// An element of a list the file does not have, or past its end: the list named, and how to give it
// (not "goals: must be an array, got {"0": ...}", as an index used to make an object).
TEST(SceneIo, OverrideIntoAMissingListElementSaysHowToGiveTheList) {
  const json j = json::parse(R"({"anchor": {}, "chain": {"links": 8}, "hoppers": []})");
  for (const char* key : {"goals.0.t=1", "chains.0.links=3", "hoppers.0.speed=1", "hoppers.2.speed=1"}) {
    const std::string e = errorOf(j, {parseOverride(key)});
    const std::string list = std::string(key).substr(0, std::string(key).find('.'));
    EXPECT_NE(e.find("is not an index of that list"), std::string::npos) << key << ": " << e;
    EXPECT_NE(e.find("--set " + list + "='[...]'"), std::string::npos) << key << ": " << e;
    EXPECT_EQ(e.find("must be an array"), std::string::npos) << key << ": " << e;
  }
  // A list given whole works.
  const Scene s = parseScene(j, "t.json", {parseOverride(R"(goals=[{"t": 1.5}])")});
  ASSERT_EQ(s.goals.size(), 1u);
  EXPECT_DOUBLE_EQ(s.goals[0].t, 1.5);
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
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no/such/scene.json"), std::string::npos);
  }
  std::filesystem::create_directories(PONYHOP_TEST_OUT);
  const std::string path = std::string(PONYHOP_TEST_OUT) + "/broken.json";
  std::ofstream(path) << "{ \"physics\": { \"dt\": 0.01, } ";
  try {
    loadScene(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
  }
}

// Hostile scene files (docs/RELIABILITY.md): each is a InputError naming the file and the field,
// never a crash, a hang or a library message.
std::string textError(const std::string& text, const std::vector<Override>& o = {}) {
  try {
    parseSceneText(text, "hostile.json", o);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SceneIoHostile, DeepNestingIsRefusedWithTheLimit) {
  // 200,000 levels overflowed the stack (the DOM's copy and dump recurse).
  const std::string deep = "{\"name\":" + std::string(200000, '[') + std::string(200000, ']') + "}";
  const std::string e = textError(deep);
  EXPECT_NE(e.find("hostile.json: name: nested deeper than " + std::to_string(kMaxJsonDepth)), std::string::npos) << e;
  // Just inside the limit is read (and then refused for its type, as any wrong value).
  const std::string ok = "{\"name\":" + std::string(kMaxJsonDepth - 1, '[') + std::string(kMaxJsonDepth - 1, ']') + "}";
  EXPECT_NE(textError(ok).find("name: must be a string"), std::string::npos) << textError(ok);
  // --set values are held to the same limit.
  const std::string o = textError("{}", {parseOverride("name=" + std::string(100000, '['))});
  EXPECT_NE(o.find("nested deeper"), std::string::npos) << o.substr(0, 300);
}

TEST(SceneIoHostile, SetValueThatIsNotUtf8IsRefused) {
  // Found by fuzz_scene (fuzz/regressions/scene/set_invalid_utf8.bin): the error message's dump
  // of the value threw nlohmann's type_error 316 and std::terminate ended the process.
  const std::string e = textError("{}", {parseOverride("physics.solver=tree\x9b\x91")});
  EXPECT_NE(e.find("--set physics.solver: the value is not valid UTF-8 text"), std::string::npos) << e;
  EXPECT_NE(textError("{}", {parseOverride("name=\xff")}).find("not valid UTF-8"), std::string::npos);
}

TEST(SceneIoHostile, NumberOverflowNamesFileAndField) {
  const std::string e = textError(R"({"physics": {"gravity": [0, 0, -9.81], "dt": -1e400}})");
  EXPECT_NE(e.find("hostile.json: physics.dt: number overflow parsing '-1e400'"), std::string::npos) << e;
  EXPECT_EQ(e.find("json.exception"), std::string::npos) << e;
}

TEST(SceneIoHostile, DuplicateKeysAreRefused) {
  const std::string e = textError(R"({"physics": {"dt": 0.01, "dt": 0.02}})");
  EXPECT_NE(e.find("hostile.json: physics.dt: the key appears twice"), std::string::npos) << e;
  // The same key in two different objects is fine.
  EXPECT_EQ(textError(R"({"physics": {"dt": 0.01}, "render": {"fps": 30}, "camera": {"mode": "fixed"}})"), "");
}

TEST(SceneIoHostile, CameraFollowMustNameABodyOfTheScene) {
  std::string e = textError(R"({"camera": {"mode": "follow", "follow": "banana"}, "anchor": {}, "chain": {}})");
  EXPECT_NE(e.find("camera.follow: \"banana\" is not a body of this scene"), std::string::npos) << e;
  EXPECT_NE(e.find("\"chain\""), std::string::npos) << e;
  e = textError(R"({"camera": {"follow": "hopper"}, "anchor": {}, "chain": {}})");
  EXPECT_NE(e.find("camera.follow: \"hopper\""), std::string::npos) << e;
  EXPECT_EQ(textError(R"({"camera": {"follow": "chain"}, "anchor": {}, "chain": {}})"), "");
}

TEST(SceneIoHostile, AHugeBadValueIsNotEchoedWhole) {
  const std::string e = textError("{\"name\": " + std::string(1, '[') + "\"" + std::string(10 << 20, 'x') + "\"]}");
  EXPECT_NE(e.find("name: must be a string"), std::string::npos) << e.substr(0, 300);
  EXPECT_LT(e.size(), 400u);
  const std::string o = textError("{}", {parseOverride("physics.dt=" + std::string(1 << 20, 'y'))});
  EXPECT_NE(o.find("physics.dt"), std::string::npos) << o.substr(0, 300);
  EXPECT_LT(o.size(), 600u);
}

TEST(SceneIoHostile, FilesThatAreNotFilesOrTooLarge) {
  const std::string dir = std::string(PONYHOP_TEST_OUT) + "/hostile_files";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto errorLoading = [](const std::string& path) -> std::string {
    try {
      loadScene(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(errorLoading(dir).find(dir + ": is a folder, not a scene file"), std::string::npos) << errorLoading(dir);
  const std::string fifo = dir + "/fifo.json";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(errorLoading(fifo).find("is a FIFO"), std::string::npos) << errorLoading(fifo);  // and did not block
  const std::string big = dir + "/big.json";
  std::ofstream(big) << "{\"name\": \"" << std::string(kMaxSceneFileBytes, 'x') << "\"}";
  const std::string e = errorLoading(big);
  EXPECT_NE(e.find("the scene file is 16.0 MB (16777228 bytes); the limit is 16.0 MB (16777216 bytes)"),
            std::string::npos)
      << e;
}

TEST(SceneIoHostile, LongChainsOnTheDenseSolverSayItsCost) {
  // The default solver is tree (O(n)): a long chain without a solver gets it, and no note.
  Scene s = parseSceneText(R"({"anchor": {}, "chain": {"links": 4096}})", "long.json");
  EXPECT_EQ(s.physics.solver, SolverKind::Tree);
  EXPECT_TRUE(s.notes.empty());
  // Dense (O(n^3)) picked by the user: kept, with its cost said.
  s = parseSceneText(R"({"physics": {"solver": "dense"}, "anchor": {}, "chain": {"links": 512}})", "long.json");
  EXPECT_EQ(s.physics.solver, SolverKind::Dense);
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_NE(s.notes[0].find("s per step"), std::string::npos) << s.notes[0];
  s = parseSceneText(R"({"anchor": {}, "chain": {"links": 8}})", "long.json",
                     {parseOverride("chain.links=4096"), parseOverride("physics.solver=dense")});
  EXPECT_EQ(s.physics.solver, SolverKind::Dense);
  ASSERT_EQ(s.notes.size(), 1u);
  // A short chain on dense: no note.
  s = parseSceneText(R"({"physics": {"solver": "dense"}, "anchor": {}, "chain": {"links": 8}})", "short.json");
  EXPECT_TRUE(s.notes.empty());
  // The shipped scenes get the default.
  for (const char* f :
       {"assets/scenes/ponytail.json", "assets/scenes/chain.json", "assets/scenes/ponytail_hopper.json"}) {
    const Scene shipped = loadScene(f);
    EXPECT_EQ(shipped.physics.solver, SolverKind::Tree) << f;
    EXPECT_TRUE(shipped.notes.empty()) << f;
  }
}

TEST(SceneIo, ReferenceListsEveryField) {
  const std::string md = sceneReferenceMarkdown();
  EXPECT_NE(md.find("`physics.dt`"), std::string::npos);
  EXPECT_NE(md.find("`chain.links`"), std::string::npos);
  EXPECT_NE(md.find("`head.animation.keys.N.t`"), std::string::npos);
}

// Adaptive dynamics: the reduced solver only, and no more joints than the chain has; a negative
// budget is out of range. Each message names the field.
TEST(SceneIo, AdaptiveDynamicsRefusesBadBudgetsAndTheMultiplierSolvers) {
  const std::string over = errorOf(json::parse(
      R"({"anchor": {}, "chain": {"links": 6}, "physics": {"solver": "featherstone", "adaptive_joints": 7}})"));
  EXPECT_NE(over.find("physics.adaptive_joints: 7 is more than the 6 joints of the chain"), std::string::npos) << over;
  const std::string negative = errorOf(
      json::parse(R"({"anchor": {}, "chain": {}, "physics": {"solver": "featherstone", "adaptive_joints": -1}})"));
  EXPECT_NE(negative.find("physics.adaptive_joints"), std::string::npos) << negative;
  const std::string tree =
      errorOf(json::parse(R"({"anchor": {}, "chain": {}, "physics": {"adaptive_tolerance": 1e-6}})"));
  EXPECT_NE(tree.find("physics.adaptive_tolerance: adaptive dynamics runs on solver 'featherstone' only"),
            std::string::npos)
      << tree;
  EXPECT_EQ(errorOf(json::parse(
                R"({"anchor": {}, "chain": {"links": 6},
                    "physics": {"solver": "featherstone", "integrator": "rk4", "adaptive_joints": 6}})")),
            "");
}

// Velocity-level joints (stabilization = velocity) are symplectic Euler's in the multiplier
// solvers; erp is a share, 0 to 1. Each message names the field.
TEST(SceneIo, VelocityLevelJointsTakeSymplecticEulerAndAShare) {
  const std::string rk4 = errorOf(
      json::parse(R"({"anchor": {}, "chain": {}, "physics": {"integrator": "rk4", "stabilization": "velocity"}})"));
  EXPECT_NE(rk4.find("physics.stabilization = 'velocity': joints at velocity level are symplectic Euler's"),
            std::string::npos)
      << rk4;
  const std::string reduced = errorOf(json::parse(
      R"({"anchor": {}, "chain": {},
          "physics": {"solver": "featherstone", "integrator": "symplectic_euler", "stabilization": "velocity"}})"));
  EXPECT_NE(reduced.find("physics.stabilization = 'velocity'"), std::string::npos) << reduced;
  const std::string share = errorOf(json::parse(
      R"({"anchor": {}, "chain": {},
          "physics": {"integrator": "symplectic_euler", "stabilization": "velocity", "erp": 1.5}})"));
  EXPECT_NE(share.find("physics.erp"), std::string::npos) << share;
  EXPECT_EQ(errorOf(json::parse(R"({"anchor": {}, "chain": {},
          "physics": {"integrator": "symplectic_euler", "stabilization": "velocity", "erp": 0.5}})")),
            "");
}

// A collision section names collisions the scene can build: the ponytail against a head (on any
// solver: featherstone too).
TEST(SceneIo, CollisionSectionNeedsAChainOnAHead) {
  const std::string no_head = errorOf(json::parse(R"({"anchor": {}, "chain": {"attach": "anchor"}, "collision": {}})"));
  EXPECT_NE(no_head.find("collision.head: the ponytail collides with the head only when chain.attach is \"head\""),
            std::string::npos)
      << no_head;
  const std::string reduced = errorOf(json::parse(
      R"({"head": {}, "chain": {"attach": "head"}, "physics": {"solver": "featherstone"}, "collision": {}})"));
  EXPECT_EQ(reduced, "") << "featherstone takes the head's contacts (impulses in joint space)";
  EXPECT_NE(errorOf(json::parse(R"({"collision": {"margin": -1}})")).find("collision.margin: must be"),
            std::string::npos);
  // Without a head to collide with, collision.head false is a valid (empty) section; options that
  // act on what the head collision builds are refused with it, not dropped silently.
  EXPECT_EQ(errorOf(json::parse(R"({"collision": {"head": false}})")), "");
  const std::string dropped = errorOf(json::parse(R"({"collision": {"head": false, "self": true}})"));
  EXPECT_NE(dropped.find("need collision.head true"), std::string::npos) << dropped;
}

// How an edit applies is the field's own metadata, inherited from its section.
TEST(SceneIo, FieldMetadataSaysHowAnEditApplies) {
  Scene s;
  FieldMeta m;
  ASSERT_TRUE(findField(s, "chain.links", m));
  EXPECT_EQ(m.apply, Apply::Restart);
  EXPECT_EQ(m.soft_max, 128.0);
  ASSERT_TRUE(findField(s, "chain.damping", m));
  EXPECT_EQ(m.apply, Apply::KeepState);
  EXPECT_TRUE(m.log);
  ASSERT_TRUE(findField(s, "camera.fov", m));  // inherited from the camera section
  EXPECT_EQ(m.apply, Apply::Live);
  ASSERT_TRUE(findField(s, "head.animation.clip", m));  // inside a Restart section
  EXPECT_EQ(m.apply, Apply::Restart);
  ASSERT_TRUE(findField(s, "render.ground", m));
  EXPECT_EQ(m.apply, Apply::Live);
  ASSERT_TRUE(findField(s, "collision.friction", m));
  EXPECT_EQ(m.apply, Apply::KeepState);
  EXPECT_FALSE(findField(s, "chain.no_such_field", m));
}

// A mesh-space anchor belongs to its mesh: another head given by --set alone is anchored from its
// own bounds (with a note saying so); given together with the anchor, or to a scene whose anchor
// is already in bounds space, nothing changes.
TEST(SceneIo, AnotherHeadMeshTakesItsAnchorFromItsOwnBounds) {
  const Scene file = loadScene("assets/scenes/ponytail.json");
  ASSERT_TRUE(file.head);
  EXPECT_EQ(file.head->anchor_space, AnchorSpace::Mesh);
  const Scene other = loadScene("assets/scenes/ponytail.json", {{"head.mesh", "assets/head/head.obj"}});
  EXPECT_EQ(other.head->anchor_space, AnchorSpace::Bounds);
  ASSERT_EQ(other.notes.size(), 1u);
  EXPECT_NE(other.notes[0].find("head.anchor_in_bounds"), std::string::npos) << other.notes[0];
  const Scene kept =
      loadScene("assets/scenes/ponytail.json", {{"head.mesh", "assets/head/head.obj"}, {"head.anchor_space", "mesh"}});
  EXPECT_EQ(kept.head->anchor_space, AnchorSpace::Mesh);
  EXPECT_TRUE(kept.notes.empty());
  const Scene same = loadScene("assets/scenes/ponytail.json", {{"head.mesh", "assets/head/head.gltf"}});
  EXPECT_EQ(same.head->anchor_space, AnchorSpace::Mesh);
}

}  // namespace
}  // namespace ponyhop

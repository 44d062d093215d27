// Issue 34: scene joints close loops. A chain hanging from a fixed anchor whose tip is tied to a
// world point: assembled at t = 0, held closed by the dense, tree and featherstone solvers, the
// three agreeing; a loop that cannot close and a redundant joint are refused by name, never a NaN.
#include <gtest/gtest.h>

#include <string>

#include "sim/scene_io.h"
#include "sim/sim.h"
#include "tests/sim/cube_head.h"

namespace ponyhop {
namespace {

using nlohmann::json;

// Six links of 5 cm from the origin, laid out along +x; the tip tied to `tie` (world, m).
Scene loopScene(const std::string& solver, const std::string& tie = "[0.12, 0.0, -0.1]") {
  return parseScene(json::parse(R"({"physics": {"solver": ")" + solver + R"(", "dt": 0.004166666666666667,
      "integrator": "rk4", "stabilization": "projection"},
    "anchor": {}, "chain": {"links": 6, "direction": [1, 0, 0]},
    "joints": [{"name": "tie", "a": {"body": "chain", "link": -1}, "b": {"body": "world", "point": )" +
                                tie + "}}]}"),
                    "loop.json");
}

std::string buildError(const Scene& scene) {
  try {
    Sim sim(scene);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Loops, EverySolverClosesTheLoopAndTheyAgree) {
  Sim dense(loopScene("dense")), tree(loopScene("tree")), feather(loopScene("featherstone"));
  double closure = 0.0, apart = 0.0, feather_apart = 0.0;
  for (int i = 0; i < 120 && dense.ok() && tree.ok() && feather.ok(); ++i) {  // half a second
    dense.step();
    tree.step();
    feather.step();
    closure = std::max({closure, dense.maxJointError(), tree.maxJointError(), feather.maxJointError()});
    apart = std::max(apart, (dense.trackedPoint() - tree.trackedPoint()).norm());
    feather_apart = std::max(feather_apart, (dense.trackedPoint() - feather.trackedPoint()).norm());
  }
  ASSERT_TRUE(dense.ok() && tree.ok() && feather.ok()) << dense.status() << tree.status() << feather.status();
  std::printf("loop: closure error at most %.3g m, dense and tree %.3g m apart, dense and featherstone %.3g m\n",
              closure, apart, feather_apart);
  EXPECT_EQ(feather.world().reduced()->loopRows(), 3);
  EXPECT_LT(closure, 1e-10);
  EXPECT_LT(apart, 1e-9);
  EXPECT_LT(feather_apart, 1e-6);
  EXPECT_NEAR((feather.trackedPoint() - Eigen::Vector3d(0.12, 0.0, -0.1)).norm(), 0.0, 1e-10) << "the tip stays tied";
  EXPECT_GT(tree.chainEnergy(), -1e3);  // finite
}

TEST(Loops, ALoopThatCannotCloseIsRefusedWithItsGap) {
  const std::string e = buildError(loopScene("tree", "[1.0, 0.0, 0.0]"));
  EXPECT_NE(e.find("joints.0 (\"tie\"): the loop cannot close; its points are 0.7 m apart"), std::string::npos) << e;
}

TEST(Loops, ARedundantJointIsRefusedPlainly) {
  Scene s = loopScene("tree");
  s.joints.push_back(s.joints[0]);  // the same tie twice: three rows too many
  const std::string e = buildError(s);
  EXPECT_NE(e.find("redundant"), std::string::npos) << e;
}

TEST(Loops, TheHeadIsClearedBeforeTheLoopCloses) {
  // Three links laid out from the cube's -y face into the cube (chain.direction leans +y): the
  // collider turns them out of it, then the tip is tied to a point beside the face. Assembled
  // after the clearing, the loop starts closed.
  Scene s = loadScene("assets/scenes/ponytail.json", {{"chain.links", "3"}});
  JointSection tie;
  tie.a = {.body = JointBody::Chain, .link = -1};
  tie.b = {.body = JointBody::Head, .point = Eigen::Vector3d(0.0, -0.07, -0.06)};
  s.joints.push_back(tie);
  const CubeAssets assets;
  Sim sim(s, &assets);
  EXPECT_LT(sim.maxJointError(), 1e-9) << "the loop starts closed";
  EXPECT_TRUE(sim.step()) << sim.status();
  EXPECT_LT(sim.maxJointError(), 1e-9);
}

TEST(Loops, JointEndsAreChecked) {
  const auto err = [](const std::string& text) {
    try {
      parseScene(json::parse(text), "t.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string chain =
      err(R"({"anchor": {}, "chain": {"links": 3}, "joints": [{"a": {"body": "chain", "chain": 1}}]})");
  EXPECT_NE(chain.find("joints.0.a.chain: 1 is not a chain of this scene"), std::string::npos) << chain;
  const std::string link =
      err(R"({"anchor": {}, "chain": {"links": 3}, "joints": [{"a": {"body": "chain", "link": 3}}]})");
  EXPECT_NE(link.find("joints.0.a.link: 3 is not a link of chain (it has 3"), std::string::npos) << link;
  const std::string fixed = err(R"({"joints": [{"a": {"body": "world"}}]})");
  EXPECT_NE(fixed.find("joints.0: both ends are on bodies that do not move"), std::string::npos) << fixed;
}

}  // namespace
}  // namespace ponyhop

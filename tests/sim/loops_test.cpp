// Issue 34: scene joints close loops. A chain hanging from a fixed anchor whose tip is tied to a
// world point: assembled at t = 0, held closed by the dense, tree and featherstone solvers, the
// three agreeing; a loop that cannot close and a redundant joint are refused by name, never a NaN.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "sim/scene_io.h"
#include "sim/sim.h"
#include "tests/sim/cube_head.h"

namespace ponyhop {
namespace {

using nlohmann::json;

// Six links of 5 cm from the origin, laid out along +x; the tip tied to `tie` (world, m).
// `dt` (s): the step, fixed (max_step_rotation 0: the same steps in every solver) when given.
Scene loopScene(const std::string& solver, const std::string& tie = "[0.12, 0.0, -0.1]", double dt = 0.0) {
  char step[96] = R"(, "dt": 0.004166666666666667)";
  if (dt > 0.0) std::snprintf(step, sizeof step, R"(, "max_step_rotation": 0, "dt": %.17g)", dt);
  return parseScene(json::parse(R"({"physics": {"solver": ")" + solver + R"(")" + std::string(step) + R"(,
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

// What agree means (docs/SOLVERS.md): dense integrates the bodies and projects, featherstone the
// joint coordinates, each with a global error O(h^4); their difference falls at that order as the
// step falls, to within 1e-9 m at 1/7680 s. The tied chain's first 1/8 s at 1/1920 and 1/7680 s.
TEST(Loops, DenseAndFeatherstoneConvergeTogetherAsTheStepFalls) {
  const auto apart = [](int per_second) {
    const double dt = 1.0 / per_second;
    Sim dense(loopScene("dense", "[0.12, 0.0, -0.1]", dt)), feather(loopScene("featherstone", "[0.12, 0.0, -0.1]", dt));
    double worst = 0.0;
    for (int i = 0; i < per_second / 8 && dense.ok() && feather.ok(); ++i) {
      dense.step();
      feather.step();
      for (int k = 0; k < 6; ++k) {
        worst = std::max(
            worst, (dense.chain()->bottom(dense.world(), k) - feather.chain()->bottom(feather.world(), k)).norm());
      }
    }
    EXPECT_TRUE(dense.ok() && feather.ok()) << dense.status() << feather.status();
    return worst;
  };
  const double coarse = apart(1920), fine = apart(7680);
  std::printf("dense - featherstone over 1/8 s: %.3g m at 1/1920 s, %.3g m at 1/7680 s (%.0fx)\n", coarse, fine,
              coarse / fine);
  EXPECT_LT(fine, 1e-9);
  EXPECT_GT(coarse, 0.0) << "two discretizations that agree to the bit: the comparison says nothing";
  EXPECT_GT(coarse / fine, 64.0) << "4x finer steps: fourth order gives 256x, third order 64x";
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

// ponytail.json cut to three links (on the test's cube head), the tip tied to a point beside the
// cube's -y face.
Scene tiedToTheHead(std::vector<Override> overrides = {}) {
  overrides.push_back({"chain.links", "3"});
  Scene s = loadScene("assets/scenes/ponytail.json", overrides);
  JointSection tie;
  tie.a = {.body = JointBody::Chain, .link = -1};
  tie.b = {.body = JointBody::Head, .point = Eigen::Vector3d(0.0, -0.07, -0.06)};
  s.joints.push_back(tie);
  return s;
}

TEST(Loops, TheHeadIsClearedBeforeTheLoopCloses) {
  // Three links laid out from the cube's -y face into the cube (chain.direction leans +y): the
  // collider turns them out of it, then the tip is tied to a point beside the face. Assembled
  // after the clearing, the loop starts closed.
  const Scene s = tiedToTheHead();
  const CubeAssets assets;
  Sim sim(s, &assets);
  EXPECT_LT(sim.maxJointError(), 1e-9) << "the loop starts closed";
  EXPECT_TRUE(sim.step()) << sim.status();
  EXPECT_LT(sim.maxJointError(), 1e-9);
}

// Featherstone takes the collider's contacts on a tree only (its contact impulses act in joint
// space and would open a loop): a looped chain against the head stops at its first contact stage
// with what to use instead.
TEST(Loops, FeatherstoneRefusesContactsOnALoopPlainly) {
  const Scene s = tiedToTheHead({{"physics.solver", "featherstone"}});
  const CubeAssets assets;
  Sim sim(s, &assets);
  sim.advanceTo(0.1);
  ASSERT_FALSE(sim.ok());
  EXPECT_NE(sim.status().find("featherstone takes contacts on a tree only"), std::string::npos) << sim.status();
  EXPECT_NE(sim.status().find("use solver = tree or dense"), std::string::npos) << sim.status();
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

// The four-bar (assets/scenes/four_bar.json): a hinge crank on the anchor turned by a servo, the
// coupler on ball joints, the follower on a hinge to the world. A quarter second at the scene's
// step: every solver holds both hinges (the linkage stays in its plane, the loop closed), the
// crank follows its servo, the solvers agree.
TEST(Loops, TheFourBarTurnsInEverySolver) {
  const auto load = [](const std::string& solver) {
    return loadScene("assets/scenes/four_bar.json", {{"physics.solver", solver}});
  };
  Sim dense(load("dense")), tree(load("tree")), feather(load("featherstone"));
  const Eigen::Vector3d o1(0.0, 0.0, 0.16);
  const auto crankAngle = [&](const Sim& s) {
    const Eigen::Vector3d d = s.chain()->bottom(s.world(), 0) - o1;
    return std::atan2(d.x(), d.z());  // about +y, from up toward +x
  };
  const double start = crankAngle(dense);
  double closure = 0.0, out_of_plane = 0.0, apart = 0.0;
  for (int i = 0; i < 60 && dense.ok() && tree.ok() && feather.ok(); ++i) {
    dense.step();
    tree.step();
    feather.step();
    for (const Sim* s : {&dense, &tree, &feather}) {
      closure = std::max(closure, s->maxJointError());
      for (int k = 0; k < 3; ++k)
        out_of_plane = std::max(out_of_plane, std::abs(s->chain()->bottom(s->world(), k).y()));
    }
    for (int k = 0; k < 2; ++k) {  // the crank's and the coupler's far ends (the follower's is pinned)
      const Eigen::Vector3d p = dense.chain()->bottom(dense.world(), k);
      apart = std::max({apart, (p - tree.chain()->bottom(tree.world(), k)).norm(),
                        (p - feather.chain()->bottom(feather.world(), k)).norm()});
    }
  }
  ASSERT_TRUE(dense.ok() && tree.ok() && feather.ok()) << dense.status() << tree.status() << feather.status();
  std::printf("four-bar: closure %.3g, out of plane %.3g m, solvers %.3g m apart; crank turned %.4f rad\n", closure,
              out_of_plane, apart, crankAngle(dense) - start);
  EXPECT_EQ(feather.world().reduced()->loopRows(), 10) << "both hinges are loop joints";
  EXPECT_LT(closure, 1e-10);
  EXPECT_LT(out_of_plane, 1e-10);
  EXPECT_LT(apart, 1e-5);
  for (const Sim* s : {&dense, &tree, &feather})
    EXPECT_NEAR(crankAngle(*s) - start, 0.25 * std::numbers::pi, 0.02) << "the servo turns the crank at pi rad/s";
}

TEST(Loops, HingesAndServosAreChecked) {
  const auto err = [](const std::string& text) {
    try {
      Sim sim(parseScene(json::parse(text), "t.json"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string axis =
      err(R"({"anchor": {}, "chain": {"links": 3}, "joints": [{"type": "hinge", "a": {"body": "chain"}}]})");
  EXPECT_NE(axis.find("joints.0.axis: a hinge needs its axis"), std::string::npos) << axis;
  const std::string type = err(R"({"anchor": {}, "chain": {}, "joints": [{"type": "slider"}]})");
  EXPECT_NE(type.find("joints.0.type"), std::string::npos) << type;
  EXPECT_NE(type.find("hinge"), std::string::npos) << type;
  const std::string servo = err(R"({"anchor": {}, "chain": {"servo": {"stiffness": 1}}})");
  EXPECT_NE(servo.find("t.json: chain.servo: a servo turns the root hinge: set chain.hinge"), std::string::npos)
      << servo;
  const std::string along = err(R"({"anchor": {}, "chain": {"direction": [0, 0, 1], "hinge": [0, 0, -1]}})");
  EXPECT_NE(along.find("chain.hinge is along chain.direction"), std::string::npos) << along;
  const std::string range = err(R"({"anchor": {}, "chain": {"servo": {"damping": -1}}})");
  EXPECT_NE(range.find("chain.servo.damping"), std::string::npos) << range;
}

}  // namespace
}  // namespace ponyhop

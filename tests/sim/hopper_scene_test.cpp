// The hopper's scenes built by the sim layer: the course runs its script; the ponytail hangs from
// the hopper's body, pulls on it, and the hopper still hops; a chain attached to a missing hopper
// and a bad hopper section are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <sstream>

#include "common/sanitizers.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

TEST(HopperScene, CourseSceneRunsItsScript) {
  Scene scene = loadScene("assets/scenes/hopper.json");
  ASSERT_TRUE(scene.hopper);
  EXPECT_EQ(scene.camera.follow, "hopper");
  Sim sim(scene);
  ASSERT_NE(sim.hopper(), nullptr);
  double max_tilt = 0.0;
  double max_leg_spin = 0.0;  // rad/s, the upper leg about its own axis
  while (sim.ok() && sim.time() < scene.duration - 1e-9) {
    sim.step();
    max_tilt = std::max(max_tilt, sim.hopper()->tilt(sim.world()));
    const RigidBody& leg = sim.world().body(sim.hopper()->model().upper);
    max_leg_spin = std::max(max_leg_spin, std::abs(leg.w.dot(leg.q * Eigen::Vector3d::UnitZ())));
  }
  // The stance servos' torque about the leg's axis is held within the toe's torsional friction:
  // before, the toe slipped at each turn and the reaction spun the leg up to 3178 rad/s.
  std::printf("[ course ] the leg spins at most %.1f rad/s about its axis\n", max_leg_spin);
  EXPECT_LT(max_leg_spin, 30.0);
  ASSERT_TRUE(sim.ok()) << sim.status();
  const RigidBody& b = sim.world().body(sim.hopper()->model().body);
  std::printf("[ course ] %.0f s: ends at (%.2f, %.2f) m, speed %.3f m/s, max tilt %.2f deg, %d hops\n", scene.duration,
              b.x.x(), b.x.y(), b.v.head<2>().norm(), max_tilt * 180.0 / std::numbers::pi, sim.hopper()->hops());
  EXPECT_LT(max_tilt * 180.0 / std::numbers::pi, 15.0);
  EXPECT_GT(b.x.head<2>().norm(), 1.0) << "the course goes somewhere";
  EXPECT_EQ(sim.followPoint(), b.x);
}

// Under the sanitizers the first 10 s (55 s of the ASan run's time for the 30), the hops bounded
// in proportion.
TEST(HopperScene, PonytailOnTheHopperHopsForThirtySeconds) {
  const double seconds = testing::fullOrSanitized(30.0, 10.0);
  Scene scene = loadScene("assets/scenes/ponytail_hopper.json");
  ASSERT_TRUE(scene.hopper && scene.chain);
  Sim sim(scene);
  const Chain* chain = sim.chain();
  ASSERT_NE(chain, nullptr);
  ASSERT_EQ(chain->parent, sim.hopper()->model().body);
  // The chain's first joint's multipliers are the force the chain exerts on the body.
  double chain_mass = 0.0;
  for (int i : chain->links) chain_mass += sim.world().body(i).mass;
  double max_tilt = 0.0, min_z = 1e9, max_joint = 0.0, pull_sum = 0.0;
  int samples = 0;
  while (sim.ok() && sim.time() < seconds - 1e-9) {
    sim.step();
    if (!sim.ok()) break;
    max_tilt = std::max(max_tilt, sim.hopper()->tilt(sim.world()));
    min_z = std::min(min_z, sim.world().body(sim.hopper()->model().body).x.z());
    max_joint = std::max(max_joint, sim.maxJointError());
    // lambda is from the last force evaluation (the contact stage's, or RK4's last stage).
    int r = 0;
    for (int j = 0; j < chain->joints.front(); ++j) r += sim.world().joints()[j]->dimension();
    pull_sum += sim.world().lambda().segment(r, 3).norm();
    ++samples;
  }
  ASSERT_TRUE(sim.ok()) << sim.status();
  const double mean_pull = pull_sum / samples;
  std::printf(
      "[ ponytail hopper ] %.0f s: max tilt %.2f deg, lowest body %.3f m, max joint error %.2e, "
      "mean pull of the chain on the body %.2f N (its weight %.2f N), %d hops\n",
      seconds, max_tilt * 180.0 / std::numbers::pi, min_z, max_joint, mean_pull, chain_mass * 9.81,
      sim.hopper()->hops());
  EXPECT_LT(max_tilt * 180.0 / std::numbers::pi, 15.0) << "the hopper must not fall";
  EXPECT_GT(min_z, 0.6);
  EXPECT_LT(max_joint, 1e-9);
  EXPECT_GT(mean_pull, 0.5 * chain_mass * 9.81) << "the chain must pull on the body (two-way coupling)";
  EXPECT_GT(sim.hopper()->hops(), 40.0 * seconds / 30.0);
}

TEST(HopperScene, SceneChecksTheHopperSection) {
  const nlohmann::json no_hopper = {{"chain", {{"attach", "hopper"}}}};
  try {
    parseScene(no_hopper, "test.json", {});
    ADD_FAILURE() << "a chain attached to a missing hopper must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("needs a hopper section"), std::string::npos) << e.what();
  }
  const nlohmann::json bad = {{"hopper", {{"min_length", 0.85}}}};
  try {
    parseScene(bad, "test.json", {});
    ADD_FAILURE() << "min_length above rest_length must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("hopper"), std::string::npos) << e.what();
  }
  const Scene ok = parseScene(nlohmann::json{{"hopper", nlohmann::json::object()}, {"chain", {{"attach", "hopper"}}}},
                              "test.json", {{"hopper.command.vx", "0.5"}});
  ASSERT_TRUE(ok.hopper.has_value());
  EXPECT_DOUBLE_EQ(ok.hopper->command.vx, 0.5);
}

}  // namespace
}  // namespace ponyhop

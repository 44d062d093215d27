// The hopper's scenes: `ponyhop sim` writes the hopper columns and takes the command keys with
// --set; the ponytail hangs from the hopper's body, pulls on it, and the hopper still hops.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <sstream>

#include "engine/scene_io.h"
#include "engine/scene_runtime.h"
#include "tests/test_util.h"

namespace ponyhop {
namespace {

using testing::readFile;
using testing::runPonyhop;
using testing::scratch;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

TEST(HopperScene, SimWritesTheHopperColumnsAndTakesCommands) {
  const std::string dir = scratch("hopper_sim");
  const std::string csv = dir + "/hop.csv";
  // The course's script is cleared so that the command alone drives the hopper.
  const auto r = runPonyhop("sim assets/scenes/hopper.json --duration 8 --set hopper.script=[] "
                            "--set hopper.command.vx=0.6 --set hopper.command.vy=-0.3 --set hopper.command.height=1.1 "
                            "--csv " + csv,
                            "hopper_sim");
  ASSERT_EQ(r.code, 0) << r.out;
  std::stringstream in(readFile(csv));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t,x,y,z,vx,vy,vz,roll,pitch,yaw,leg_length,phase,foot_x,foot_y,foot_z,contact,knee_error");
  int rows = 0, contact_rows = 0;
  std::set<std::string> phases;
  std::vector<std::string> last;
  double x4 = 0, y4 = 0, max_z = 0;
  while (std::getline(in, line)) {
    const auto c = split(line);
    ASSERT_EQ(c.size(), 17u) << line;
    ++rows;
    phases.insert(c[11]);
    contact_rows += c[15] == "1";
    EXPECT_GT(std::stod(c[14]), -2e-3) << "foot below the ground: " << line;
    EXPECT_LT(std::stod(c[16]), 1e-9) << "knee error: " << line;
    const double t = std::stod(c[0]);
    if (std::abs(t - 4.0) < 1e-9) {
      x4 = std::stod(c[1]);
      y4 = std::stod(c[2]);
    }
    if (t > 4.0) max_z = std::max(max_z, std::stod(c[3]));
    last = c;
  }
  EXPECT_EQ(rows, 8001) << "one row per millisecond";
  EXPECT_EQ(phases, (std::set<std::string>{"flight", "loading", "compression", "thrust", "unloading"}));
  EXPECT_GT(contact_rows, 1000);
  const double vx = (std::stod(last[1]) - x4) / 4.0, vy = (std::stod(last[2]) - y4) / 4.0;
  std::printf("[ sim --set ] mean velocity 4-8 s (%.3f, %.3f) m/s (command (0.6, -0.3)), highest apex %.3f m (1.1)\n", vx,
              vy, max_z);
  EXPECT_NEAR(vx, 0.6, 0.1);
  EXPECT_NEAR(vy, -0.3, 0.1);
  EXPECT_NEAR(max_z, 1.1, 0.03);
}

TEST(HopperScene, CourseSceneRunsItsScript) {
  Scene scene = loadScene("assets/scenes/hopper.json");
  ASSERT_TRUE(scene.hopper);
  EXPECT_EQ(scene.camera.follow, "hopper");
  SceneRuntime rt(scene);
  ASSERT_NE(rt.hopper(), nullptr);
  double max_tilt = 0.0;
  while (rt.ok() && rt.time() < scene.duration - 1e-9) {
    rt.step();
    max_tilt = std::max(max_tilt, rt.hopper()->tilt(rt.world()));
  }
  ASSERT_TRUE(rt.ok()) << rt.status();
  const RigidBody& b = rt.world().body(rt.hopper()->model().body);
  std::printf("[ course ] %.0f s: ends at (%.2f, %.2f) m, speed %.3f m/s, max tilt %.2f deg, %d hops\n", scene.duration,
              b.x.x(), b.x.y(), b.v.head<2>().norm(), max_tilt * 180.0 / std::numbers::pi, rt.hopper()->hops());
  EXPECT_LT(max_tilt * 180.0 / std::numbers::pi, 15.0);
  EXPECT_GT(b.x.head<2>().norm(), 1.0) << "the course goes somewhere";
  EXPECT_EQ(rt.followPoint(), b.x);
}

TEST(HopperScene, PonytailOnTheHopperHopsForThirtySeconds) {
  Scene scene = loadScene("assets/scenes/ponytail_hopper.json");
  ASSERT_TRUE(scene.hopper && scene.chain);
  SceneRuntime rt(scene);
  const Chain* chain = rt.chain();
  ASSERT_NE(chain, nullptr);
  ASSERT_EQ(chain->parent, rt.hopper()->model().body);
  // The chain's first joint's multipliers are the force the chain exerts on the body.
  double chain_mass = 0.0;
  for (int i : chain->links) chain_mass += rt.world().body(i).mass;
  double max_tilt = 0.0, min_z = 1e9, max_joint = 0.0, pull_sum = 0.0;
  int samples = 0;
  while (rt.ok() && rt.time() < 30.0 - 1e-9) {
    rt.step();
    if (!rt.ok()) break;
    max_tilt = std::max(max_tilt, rt.hopper()->tilt(rt.world()));
    min_z = std::min(min_z, rt.world().body(rt.hopper()->model().body).x.z());
    max_joint = std::max(max_joint, rt.maxJointError());
    // lambda is from the last force evaluation (the contact stage's, or RK4's last stage).
    int r = 0;
    for (int j = 0; j < chain->joints.front(); ++j) r += rt.world().joints()[j]->dimension();
    pull_sum += rt.world().lambda().segment(r, 3).norm();
    ++samples;
  }
  ASSERT_TRUE(rt.ok()) << rt.status();
  const double mean_pull = pull_sum / samples;
  std::printf("[ ponytail hopper ] 30 s: max tilt %.2f deg, lowest body %.3f m, max joint error %.2e, "
              "mean pull of the chain on the body %.2f N (its weight %.2f N), %d hops\n",
              max_tilt * 180.0 / std::numbers::pi, min_z, max_joint, mean_pull, chain_mass * 9.81, rt.hopper()->hops());
  EXPECT_LT(max_tilt * 180.0 / std::numbers::pi, 15.0) << "the hopper must not fall";
  EXPECT_GT(min_z, 0.6);
  EXPECT_LT(max_joint, 1e-9);
  EXPECT_GT(mean_pull, 0.5 * chain_mass * 9.81) << "the chain must pull on the body (two-way coupling)";
  EXPECT_GT(rt.hopper()->hops(), 40);
}

}  // namespace
}  // namespace ponyhop

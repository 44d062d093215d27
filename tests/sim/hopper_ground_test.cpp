// collision.ground: the hopper's body and legs land on the ground when it falls, and two hoppers
// bump instead of passing through each other. Each check is run without the collisions too, to
// show it would fail there.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>

#include "physics/shapes.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

// The lowest point of the hopper's hull and legs (the capsules as drawn; the toe has its own
// contact and is left out): the hull's axis ends less its radius, the legs' ends less theirs.
double lowestPoint(const Sim& sim, const Hopper& h) {
  const HopperModel& m = h.model();
  const HopperParams& p = m.params;
  const World& w = sim.world();
  const RigidBody& body = w.body(m.body);
  const RigidBody& upper = w.body(m.upper);
  const RigidBody& foot = w.body(m.foot);
  const double rz = 0.5 * p.body_size.z(), half = 0.5 * p.body_size.x() - rz;
  const Eigen::Vector3d ex = body.q * Eigen::Vector3d::UnitX();
  double low = std::min((body.x + half * ex).z(), (body.x - half * ex).z()) - rz;
  const Eigen::Vector3d eu = upper.q * Eigen::Vector3d::UnitZ();
  low = std::min(low, (upper.x - 0.5 * p.upper_length * eu).z() - 0.8 * p.upper_radius);
  const Eigen::Vector3d ef = foot.q * Eigen::Vector3d::UnitZ();
  low = std::min(low, (foot.x + 0.5 * p.foot_length * ef).z() - p.foot_radius);
  return low;
}

struct FallRun {
  double lowest = std::numeric_limits<double>::infinity();  // m, over the whole run
  double end_height = 0.0;                                  // m, the body's centre at the end
  // m: over the last second, the largest distance of the body's centre from where it was a
  // second before the end (its controller keeps servoing the leg, so it rocks where it lies)
  double last_second_travel = 0.0;
};

FallRun runFall(bool ground) {
  Scene scene = loadScene("assets/scenes/hopper_fall.json",
                          {{"collision.ground", ground ? "true" : "false"}, {"collision.head", "false"}});
  Sim sim(scene);
  FallRun r;
  const int body = sim.hopper()->model().body;
  Eigen::Vector3d second_before = Eigen::Vector3d::Zero();
  bool last_second = false;
  while (sim.ok() && sim.time() < scene.duration - 1e-9) {
    sim.step();
    r.lowest = std::min(r.lowest, lowestPoint(sim, *sim.hopper()));
    const Eigen::Vector3d x = sim.world().body(body).x;
    if (!last_second && sim.time() >= scene.duration - 1.0 - 1e-9) {
      last_second = true;
      second_before = x;
    }
    if (last_second) r.last_second_travel = std::max(r.last_second_travel, (x - second_before).norm());
  }
  EXPECT_TRUE(sim.ok()) << sim.status();
  const RigidBody& b = sim.world().body(sim.hopper()->model().body);
  r.end_height = b.x.z();
  return r;
}

TEST(HopperGround, AFallenHopperLiesOnTheGround) {
  const FallRun on = runFall(true);
  std::printf(
      "[ fall ] with collision.ground: lowest point %.4f m, body ends at z = %.3f m, moved %.3f m in the last second\n",
      on.lowest, on.end_height, on.last_second_travel);
  EXPECT_LT(on.end_height, 0.4) << "the hopper was to fall over";
  EXPECT_GT(on.lowest, -2e-3) << "the hull or a leg went into the ground";
  EXPECT_LT(on.last_second_travel, 0.15) << "it lies there (rocking under its leg's servos, not travelling)";

  const FallRun off = runFall(false);
  std::printf("[ fall ] without: lowest point %.3f m, body ends at z = %.3f m\n", off.lowest, off.end_height);
  EXPECT_LT(off.lowest, -0.1) << "without the collisions the body falls through the ground";
}

// Two hoppers hop toward each other; their hulls bump instead of passing through. The gap between
// the two hulls (capsules as drawn) is measured by the narrow phase (physics/shapes.h).
double smallestHullGap(bool ground) {
  const std::string text = R"({
    "duration": 8.0,
    "physics": { "dt": 0.001, "integrator": "rk4", "stabilization": "projection" },
    "hopper": { "position": [-1.2, 0.0, 1.05], "script": [ { "t": 0.0, "vx": 0.0 }, { "t": 1.0, "vx": 0.6 } ] },
    "hoppers": [ { "position": [1.2, 0.0, 1.05], "command": { "heading": 180.0 },
                   "script": [ { "t": 0.0, "vx": 0.0, "heading": 180.0 }, { "t": 1.0, "vx": -0.6, "heading": 180.0 } ] } ],
    "collision": { "ground": )" +
                           std::string(ground ? "true" : "false") + R"(, "head": false } })";
  const Scene scene = parseSceneText(text, "two hoppers");
  Sim sim(scene);
  EXPECT_EQ(sim.hoppers().size(), 2u);
  const HopperParams& p = sim.hoppers()[0]->model().params;
  const double rz = 0.5 * p.body_size.z();
  const Shape hull = Shape::capsule(0.5 * p.body_size.x() - rz, rz, rz, Eigen::Vector3d::Zero(),
                                    Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY())));
  double smallest = std::numeric_limits<double>::infinity();
  std::vector<ContactPoint> points;
  while (sim.ok() && sim.time() < scene.duration - 1e-9) {
    sim.step();
    const RigidBody& a = sim.world().body(sim.hoppers()[0]->model().body);
    const RigidBody& b = sim.world().body(sim.hoppers()[1]->model().body);
    points.clear();
    if (collide(place(hull, a.x, a.q), place(hull, b.x, b.q), 0.5, points) > 0)
      smallest = std::min(smallest, points.front().gap);
  }
  EXPECT_TRUE(sim.ok()) << sim.status();
  return smallest;
}

TEST(HopperGround, TwoHoppersBumpInsteadOfPassingThrough) {
  const double on = smallestHullGap(true);
  const double off = smallestHullGap(false);
  std::printf("[ two ] smallest gap between the hulls: %.4f m with collision.ground, %.3f m without\n", on, off);
  EXPECT_LT(on, 0.01) << "they were to meet";
  EXPECT_GT(on, -3e-3) << "the hulls went into each other";
  EXPECT_LT(off, -0.1) << "without the collisions they pass through each other";
}

TEST(HopperGround, GroundNeedsAHopper) {
  try {
    parseSceneText(R"({"anchor": {}, "chain": {"attach": "anchor"}, "collision": {"ground": true, "head": false}})",
                   "no hopper");
    FAIL() << "collision.ground without a hopper was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("collision.ground: the scene has no hopper"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ponyhop

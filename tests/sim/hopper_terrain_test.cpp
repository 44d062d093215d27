// Terrain (physics/models/terrain.h): the ground's tangent plane under a point, and the hopper of
// assets/scenes/hopper_terrain.json running up a slope, across a plateau, down a step and over a
// low step: its toe stands on the boxes (never in them) and it gets to the far side upright.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "physics/models/terrain.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

const double kDeg = std::numbers::pi / 180.0;

TEST(Terrain, TheTangentPlaneOfABoxASlopeAndThePlane) {
  const Terrain flat;
  const Terrain::Surface p = flat.at(Eigen::Vector3d(0.3, -2.0, 0.25));
  EXPECT_EQ(p.distance, 0.25);
  EXPECT_EQ(p.normal, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(p.level, 0.0);

  TerrainBox step;
  step.center = Eigen::Vector3d(2.0, 0.0, 0.05);
  step.size = Eigen::Vector3d(2.0, 2.0, 0.1);
  TerrainBox slope;
  slope.center = Eigen::Vector3d(-3.0, 0.0, 0.0);
  slope.size = Eigen::Vector3d(2.0, 2.0, 0.2);
  slope.rotation = Eigen::Vector3d(0.0, -10.0, 0.0);
  const Terrain t({step, slope});
  // Above the step's top face: the face's plane.
  const Terrain::Surface top = t.at(Eigen::Vector3d(2.2, 0.1, 0.3));
  EXPECT_NEAR(top.distance, 0.2, 1e-12);
  EXPECT_NEAR((top.normal - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(top.level, 0.1, 1e-12);
  // Beside the step, low: the plane z = 0 is nearer than the step's side.
  EXPECT_EQ(t.at(Eigen::Vector3d(0.5, 0.0, 0.02)).normal, Eigen::Vector3d::UnitZ());
  // Above the slope's middle: the normal tilted by 10 degrees toward -x.
  const Terrain::Surface s = t.at(Eigen::Vector3d(-3.0, 0.0, 0.5));
  EXPECT_NEAR(std::acos(s.normal.z()) / kDeg, 10.0, 1e-9);
  EXPECT_LT(s.normal.x(), 0.0);
  EXPECT_NEAR(s.distance, 0.5 * std::cos(10.0 * kDeg) - 0.1, 1e-9);
}

TEST(HopperTerrain, RunsUpASlopeAcrossAPlateauAndDownAStep) {
  const Scene scene = loadScene("assets/scenes/hopper_terrain.json");
  Sim sim(scene);
  ASSERT_NE(sim.terrain(), nullptr);
  const Hopper& h = *sim.hopper();
  const HopperParams& p = h.params();
  double deepest = 0.0, max_tilt = 0.0, lowest_body = 1e9, highest_stance = -1e9;
  int stances_on_boxes = 0;
  bool was_in_contact = false;
  while (sim.ok() && sim.time() < scene.duration - 1e-9) {
    sim.step();
    const World& w = sim.world();
    const Eigen::Vector3d toe = h.contact().center(w);
    deepest = std::min(deepest, sim.terrain()->at(toe).distance - p.toe_radius);
    max_tilt = std::max(max_tilt, h.tilt(w));
    lowest_body = std::min(lowest_body, w.body(h.model().body).x.z());
    if (h.inContact()) {
      const double ground = h.contact().groundHeight(w);
      highest_stance = std::max(highest_stance, ground);
      if (!was_in_contact && ground > 0.01) ++stances_on_boxes;
    }
    was_in_contact = h.inContact();
  }
  ASSERT_TRUE(sim.ok()) << sim.status();
  const Eigen::Vector3d end = sim.world().body(h.model().body).x;
  std::printf(
      "[ terrain ] deepest toe %.2e m, max tilt %.1f deg, lowest body %.3f m, highest stance %.3f m, "
      "%d touchdowns on the boxes, ends at x = %.2f m\n",
      deepest, max_tilt / kDeg, lowest_body, highest_stance, stances_on_boxes, end.x());
  EXPECT_GT(deepest, -1e-3) << "the toe never sinks into the terrain";
  EXPECT_GT(highest_stance, 0.15) << "it stood on the plateau";
  EXPECT_GE(stances_on_boxes, 6);
  EXPECT_GT(end.x(), 7.5) << "it crossed everything (the last step ends at x = 7.2 m)";
  EXPECT_LT(max_tilt, 25.0 * kDeg);
  EXPECT_GT(lowest_body, 0.5) << "it never fell";
}

}  // namespace
}  // namespace ponyhop

// Helpers shared by the physics tests: the exact methods' parameters, running a world for a while,
// comparing chain poses, and a hopper in a world of its own.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "physics/models/chain.h"
#include "physics/models/hopper.h"
#include "physics/spherical_joint.h"
#include "physics/world.h"

namespace ponyhop::testing {

constexpr double kRad = 180.0 / std::numbers::pi;  // degrees per radian

// RK4 with projection: the exact multiplier method the solver tests compare (fixed dt unless
// max_step_rotation is left at its default; 1/960 s unless told).
inline PhysicsParams exactPhysics(SolverKind solver, double dt = 1.0 / 960.0) {
  PhysicsParams pp;
  pp.dt = dt;
  pp.integrator = Integrator::RK4;
  pp.solver = solver;
  pp.stabilization = Stabilization::Projection;
  return pp;
}

// Steps `world` for `seconds` (to the nearest step); expects it to stay healthy.
inline void runFor(World& world, double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / world.params().dt));
  for (int i = 0; i < steps && world.ok(); ++i) world.step();
  EXPECT_TRUE(world.ok()) << world.status();
}

// Largest |E - E0| over `steps` steps from the current state (J); expects the world to stay healthy.
inline double maxEnergyDrift(World& world, int steps) {
  const double e0 = world.energy();
  double worst = 0.0;
  for (int i = 0; i < steps && world.ok(); ++i) {
    world.step();
    worst = std::max(worst, std::abs(world.energy() - e0));
  }
  EXPECT_TRUE(world.ok()) << world.status();
  return worst;
}

// a / b within [lo, hi] (convergence ratios when dt halves).
inline void expectRatio(double a, double b, double lo, double hi) {
  EXPECT_GT(a / b, lo) << a << " / " << b;
  EXPECT_LT(a / b, hi) << a << " / " << b;
}

// Centres of the chain's links, root first.
inline std::vector<Eigen::Vector3d> linkPositions(const ChainWorld& cw) {
  std::vector<Eigen::Vector3d> out;
  for (int id : cw.chain.links) out.push_back(cw.world.body(id).x);
  return out;
}

// Largest distance between corresponding points.
inline double maxDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double d = 0.0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, (a[i] - b[i]).norm());
  return d;
}

// The hopper tests' physics: RK4 with projection at 1 ms (the hopper scenes' settings).
inline PhysicsParams hopperPhysics() {
  PhysicsParams pp;
  pp.dt = 1e-3;
  pp.integrator = Integrator::RK4;
  pp.stabilization = Stabilization::Projection;
  return pp;
}

// A hopper alone in its world: world.step() runs its Think, its muscles and its foot contact.
struct HopperWorld {
  World world;
  std::shared_ptr<Hopper> hopper;
  explicit HopperWorld(const HopperParams& hp, const PhysicsParams& pp = hopperPhysics())
      : world(pp), hopper(Hopper::add(world, hp)) {}
  const RigidBody& body() const { return world.body(hopper->model().body); }
};

// A spherical joint at the midpoint of two chains' tips (each tip's point in its own frame).
inline void joinTips(World& world, const Chain& a, const Chain& b) {
  const Eigen::Vector3d mid = 0.5 * (a.tip(world) + b.tip(world));
  const RigidBody& ta = world.body(a.links.back());
  const RigidBody& tb = world.body(b.links.back());
  world.addJoint(std::make_unique<SphericalJoint>(a.links.back(), ta.q.conjugate() * (mid - ta.x), b.links.back(),
                                                  tb.q.conjugate() * (mid - tb.x)));
}

}  // namespace ponyhop::testing

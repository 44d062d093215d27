// The toe's friction in the solve (physics/models/hopper_foot.h): a hopper thrown sideways onto a slippery
// floor lands sliding. The landing's impulse comes from one cone problem (normal and friction
// together), so it removes energy and never turns the slip around; from the landing on, kinetic
// friction mu N acts with the normal force N of the same joint-force solve (no step without
// friction, no N one step old).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "common/physics_util.h"
#include "physics/models/hopper.h"

namespace ponyhop {
namespace {

// The contact's first row in world.lambda().
int contactRow(const World& world, const GroundContact& c) {
  int row = 0;
  for (int j = 0; j < c.jointIndex(); ++j) row += world.joints()[j]->dimension();
  return row;
}

struct SlideRun {
  int sliding_touchdowns = 0, slide_steps = 0, frictionless_slide_steps = 0;
  double worst_consistency = 0.0;  // max |lambda_n - N| / N over the steps in slide
  double max_reversal = -1e300, max_gain = -1e300;
  double slide_distance = 0.0;  // m, the toe's travel while sliding
};

SlideRun throwOnto(double mu, double speed) {
  HopperParams hp;
  hp.friction = mu;
  testing::HopperWorld run(hp);
  World& world = run.world;
  for (RigidBody& b : world.bodies())
    if (b.isDynamic()) b.v = Eigen::Vector3d(speed, 0.0, 0.0);
  SlideRun r;
  const GroundContact& contact = run.hopper->contact();
  Eigen::Vector3d last_toe = contact.point(world);
  while (world.ok() && world.time() < 1.5) {
    world.step();
    if (!world.ok()) break;
    const ContactState& s = contact.state();
    const Eigen::Vector3d toe = contact.point(world);
    if (s.mode == ContactMode::Slide) {
      ++r.slide_steps;
      r.slide_distance += (toe - last_toe).norm();
      if (!(s.friction_force.norm() > 0.0)) ++r.frictionless_slide_steps;
      const double lambda_n = world.lambda()(contactRow(world, contact));
      r.worst_consistency = std::max(r.worst_consistency, std::abs(lambda_n - s.normal_force) / s.normal_force);
      // The friction applied is mu times that N, against the slip.
      EXPECT_NEAR(s.friction_force.norm(), mu * s.normal_force, 1e-9 * s.normal_force);
    }
    last_toe = toe;
  }
  EXPECT_TRUE(world.ok()) << world.status();
  const ContactStats& cs = contact.stats();
  r.sliding_touchdowns = cs.sliding_touchdowns;
  r.max_reversal = cs.max_slip_reversal;
  r.max_gain = cs.max_touchdown_energy_gain;
  std::printf(
      "[ slide ] mu %.2f thrown at %.1f m/s: %d touchdowns (%d sliding), %d steps sliding over %.3f m, "
      "|lambda_n - N|/N <= %.2g, slip reversal <= %.2g m/s, touchdown energy change <= %.3f J, Painleve %d\n",
      mu, speed, cs.touchdowns, cs.sliding_touchdowns, r.slide_steps, r.slide_distance, r.worst_consistency,
      r.max_reversal, r.max_gain, cs.inconsistent_slides);
  return r;
}

TEST(HopperSlide, ASlidingLandingSlowsTheSlipAndFrictionActsFromTheFirstStep) {
  for (double mu : {0.2, 0.4}) {
    const SlideRun r = throwOnto(mu, 3.0);
    ASSERT_GE(r.sliding_touchdowns, 1) << "the throw was to land sliding";
    EXPECT_GT(r.slide_steps, 10);
    EXPECT_EQ(r.frictionless_slide_steps, 0) << "a step in slide without friction";
    EXPECT_LT(r.worst_consistency, 1e-9) << "N of the friction is the normal multiplier of the same solve";
    EXPECT_LE(r.max_reversal, 1e-12) << "the landing's friction impulse turned the slip around";
    EXPECT_LE(r.max_gain, 1e-9) << "an inelastic landing cannot add kinetic energy";
  }
}

}  // namespace
}  // namespace ponyhop

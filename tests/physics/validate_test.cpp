// Physics refuses nonsense with a message that names the field and the allowed range, and a
// world that goes wrong stops with a status naming the time, the stage and the likely cause.
#include "physics/validate.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "physics/models/chain.h"
#include "physics/spherical_joint.h"

namespace ponyhop {
namespace {

// gtest only (no gmock): a substring check that prints the whole message on failure.
::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << part << "\" not in \"" << text << "\"";
}
::testing::AssertionResult Contains(const Status& status, const std::string& part) {
  if (status.ok()) return ::testing::AssertionFailure() << "ok, expected an error with \"" << part << "\"";
  return Contains(status.message(), part);
}

TEST(PhysicsParams, DefaultsAreValid) {
  EXPECT_TRUE(validate(PhysicsParams{}).ok());
  EXPECT_TRUE(validate(ChainParams{}).ok());
  EXPECT_TRUE(validate(AnchorParams{}).ok());
}

TEST(PhysicsParams, BadValuesNameFieldAndRange) {
  ChainParams c;
  c.links = 0;
  EXPECT_TRUE(Contains(validate(c), "chain.links = 0"));
  EXPECT_TRUE(Contains(validate(c), "[1, 4096]"));
  c = {};
  c.length = -0.1;
  EXPECT_TRUE(Contains(validate(c), "chain.length = -0.1"));
  EXPECT_TRUE(Contains(validate(c), "m"));
  c = {};
  c.mass = 0.0;
  EXPECT_TRUE(Contains(validate(c), "chain.mass = 0"));
  c = {};
  c.radius = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(Contains(validate(c), "chain.radius = nan"));
  c = {};
  c.direction.setZero();
  EXPECT_TRUE(Contains(validate(c), "chain.direction"));

  PhysicsParams p;
  p.dt = 0.0;
  EXPECT_TRUE(Contains(validate(p), "physics.dt = 0"));
  p = {};
  p.dt = -1.0 / 240.0;
  EXPECT_TRUE(Contains(validate(p), "physics.dt"));
  p = {};
  p.substeps = 0;
  EXPECT_TRUE(Contains(validate(p), "physics.substeps = 0"));
  p = {};
  p.gravity.z() = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(Contains(validate(p), "physics.gravity[2] = inf"));

  AnchorParams a;
  a.velocity.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(Contains(validate(a), "anchor.velocity[0]"));
}

TEST(PhysicsParams, WorldRefusesToBuildOrStepNonsense) {
  PhysicsParams p;
  p.dt = std::numeric_limits<double>::quiet_NaN();
  World bad(p);
  EXPECT_FALSE(bad.ok());
  EXPECT_TRUE(Contains(bad.status(), "physics.dt"));
  bad.step();
  EXPECT_EQ(bad.time(), 0.0);

  ChainParams c;
  c.links = -3;
  ChainWorld cw = makeChainWorld(PhysicsParams{}, c, AnchorParams{});
  EXPECT_FALSE(cw.world.ok());
  EXPECT_TRUE(Contains(cw.world.status(), "chain.links = -3"));
  EXPECT_TRUE(cw.chain.empty());

  World w(PhysicsParams{});
  RigidBody massless;
  massless.name = "ghost";
  massless.mass = 0.0;
  w.addDynamicBody(massless);
  EXPECT_TRUE(Contains(w.status(), "'ghost'"));

  World k(PhysicsParams{});
  const int a = k.addKinematicBody(nullptr, "a");
  const int b = k.addKinematicBody(nullptr, "b");
  k.addJoint(std::make_unique<SphericalJoint>(a, Eigen::Vector3d::Zero(), b, Eigen::Vector3d::Zero()));
  EXPECT_TRUE(Contains(k.status(), "prescribed"));
}

// A state poisoned from outside (or a diverging run) stops the world at the first stage that
// sees it, with the time and a likely cause, instead of stepping NaN along.
TEST(PhysicsParams, NonFiniteStateStopsWithStatus) {
  ChainWorld cw = makeChainWorld(PhysicsParams{}, ChainParams{}, AnchorParams{});
  for (int i = 0; i < 24; ++i) cw.world.step();
  ASSERT_TRUE(cw.world.ok());
  cw.world.body(cw.chain.links[3]).w.x() = std::numeric_limits<double>::quiet_NaN();
  cw.world.step();
  EXPECT_FALSE(cw.world.ok());
  EXPECT_TRUE(Contains(cw.world.status(), "t = 0.1 s"));
  EXPECT_TRUE(Contains(cw.world.status(), "stage 'external forces'"));
  EXPECT_TRUE(Contains(cw.world.status(), "'link 3'"));
  EXPECT_TRUE(Contains(cw.world.status(), "Likely cause"));
  const double t = cw.world.time();
  cw.world.step();
  EXPECT_EQ(cw.world.time(), t);  // stopped

  // A step far too large for a stiff, heavily damped chain runs away: stopped in a stage.
  PhysicsParams coarse;
  coarse.dt = 0.1;
  coarse.integrator = Integrator::SymplecticEuler;
  coarse.stabilization = Stabilization::None;
  ChainParams stiff;
  stiff.stiffness = 100.0;
  stiff.damping = 10.0;
  ChainWorld blow = makeChainWorld(coarse, stiff, AnchorParams{});
  for (int i = 0; i < 1000 && blow.world.ok(); ++i) blow.world.step();
  EXPECT_FALSE(blow.world.ok());
  EXPECT_TRUE(Contains(blow.world.status(), "stage '"));
  for (const RigidBody& b : blow.world.bodies()) EXPECT_TRUE(b.x.allFinite()) << blow.world.status();
}

}  // namespace
}  // namespace ponyhop

// The hopper's joints (and the four-bar's hinge) against what is known: the prismatic knee's, the
// hinge's and the ground contact's Jacobians and velocity-product terms against finite differences along exact free
// motions, the knee holding without any stabilization while the leg tumbles, and physical nonsense refused.
#include <gtest/gtest.h>

#include <random>

#include "physics/hinge_joint.h"
#include "physics/models/hopper.h"
#include "physics/models/hopper_foot.h"
#include "physics/prismatic_joint.h"

namespace ponyhop {
namespace {

// A body moving freely with constant v and world-frame w: x(t) = x + t v, q(t) = exp(t w) q.
// Its acceleration is zero, so along this path C'' = J'q' (the bias) exactly.
RigidBody advanced(const RigidBody& b, double t) {
  RigidBody o = b;
  o.x = b.x + t * b.v;
  o.q = (quaternionFromRotationVector(t * b.w) * b.q).normalized();
  return o;
}

RigidBody randomBody(std::mt19937& rng, const Eigen::Vector3d& around) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RigidBody b;
  b.x = around + 0.05 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  b.q = quaternionFromRotationVector(0.1 * Eigen::Vector3d(u(rng), u(rng), u(rng)));
  b.v = Eigen::Vector3d(u(rng), u(rng), u(rng));
  b.w = 3.0 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  return b;
}

// C' = J q' and C'' = J'q' (zero accelerations) by central differences; returns the largest
// relative mismatch.
void expectDerivativesMatch(const Constraint& c, const RigidBody& a, const RigidBody& b, bool b_is_world) {
  const double h = 1e-4;
  const auto at = [&](double t) { return c.rowsAt(advanced(a, t), b_is_world ? b : advanced(b, t)); };
  const ConstraintRows r0 = at(0.0), rp = at(h), rm = at(-h);
  Vector6d qa, qb;
  qa << a.v, a.w;
  qb << b.v, b.w;
  const Eigen::VectorXd cdot = r0.ja * qa + r0.jb * qb;
  const Eigen::VectorXd cdot_fd = (rp.C - rm.C) / (2.0 * h);
  const Eigen::VectorXd cddot_fd = (rp.C - 2.0 * r0.C + rm.C) / (h * h);
  for (int i = 0; i < c.dimension(); ++i) {
    EXPECT_NEAR(cdot(i), cdot_fd(i), 1e-6 * (1.0 + std::abs(cdot(i)))) << c.typeName() << " row " << i << ": J q'";
    EXPECT_NEAR(r0.bias(i), cddot_fd(i), 1e-4 * (1.0 + std::abs(r0.bias(i))))
        << c.typeName() << " row " << i << ": J'q'";
  }
}

TEST(HopperKnee, PrismaticJacobianAndBiasMatchFiniteDifferences) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const RigidBody a = randomBody(rng, Eigen::Vector3d(0.0, 0.0, 0.6));
    const RigidBody b = randomBody(rng, Eigen::Vector3d(0.0, 0.0, 0.3));
    // Points off the centres of mass and a tilted joint frame exercise every term.
    const PrismaticJoint knee(
        0, Eigen::Vector3d(0.01, -0.02, -0.1), quaternionFromRotationVector(Eigen::Vector3d(0.2, -0.1, 0.3)), 1,
        Eigen::Vector3d(-0.03, 0.01, 0.15), quaternionFromRotationVector(Eigen::Vector3d(0.1, 0.2, -0.2)));
    expectDerivativesMatch(knee, a, b, false);
  }
}

// The four-bar's hinge (physics/hinge_joint.h) by the same check: its ball rows and its two axis
// rows, a tilted axis, points off the centres.
TEST(HopperKnee, HingeJacobianAndBiasMatchFiniteDifferences) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const RigidBody a = randomBody(rng, Eigen::Vector3d(0.0, 0.0, 0.6));
    const RigidBody b = randomBody(rng, Eigen::Vector3d(0.0, 0.0, 0.3));
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3, 1.0, -0.2).normalized();
    const HingeJoint hinge(0, Eigen::Vector3d(0.01, -0.02, -0.1), a.q.conjugate() * axis, 1,
                           Eigen::Vector3d(-0.03, 0.01, 0.15), b.q.conjugate() * axis);
    expectDerivativesMatch(hinge, a, b, false);
  }
}

TEST(HopperKnee, ContactJacobianAndBiasMatchFiniteDifferences) {
  std::mt19937 rng(11);
  for (ContactMode mode : {ContactMode::Stick, ContactMode::Slide}) {
    for (int trial = 0; trial < 10; ++trial) {
      auto state = std::make_shared<ContactState>();
      state->mode = mode;
      state->twist = true;
      state->anchor = Eigen::Vector3d(0.01, -0.02, 0.03);
      state->twist_ref = Eigen::Vector3d(0.6, 0.8, 0.0);
      const FootContact contact(0, Eigen::Vector3d(0.0, 0.0, -0.2), 0.03, state);
      const RigidBody foot = randomBody(rng, Eigen::Vector3d(0.0, 0.0, 0.25));
      expectDerivativesMatch(contact, foot, worldBody(), true);
    }
  }
}

// The knee's five rows hold without stabilization (acceleration-level constraints only, RK4):
// an upper leg and a foot tumbling freely, the foot oscillating on a spring along the axis. Wrong
// Jacobians or bias terms make C drift at once; right ones leave only the integrator's error.
TEST(HopperKnee, HoldsWhileTumblingWithoutStabilization) {
  PhysicsParams pp;
  pp.dt = 1e-3;
  pp.gravity.setZero();
  pp.stabilization = Stabilization::None;
  World world(pp);
  RigidBody upper;
  upper.mass = 0.7;
  upper.inertia = Eigen::Vector3d(0.012, 0.012, 4e-4);
  upper.w = Eigen::Vector3d(2.0, -1.0, 3.0);
  const int a = world.addDynamicBody(upper);
  RigidBody foot;
  foot.mass = 0.3;
  foot.inertia = Eigen::Vector3d(0.005, 0.005, 4e-5);
  foot.x = Eigen::Vector3d(0.0, 0.0, -0.4);
  const int b = world.addDynamicBody(foot);
  world.addJoint(std::make_unique<PrismaticJoint>(a, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), b,
                                                  Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()));
  world.body(b).v = world.body(a).velocityAt(world.body(b).x) + Eigen::Vector3d(0.0, 0.0, -0.5);
  world.projectVelocities();
  // A spring along the axis: the slide moves while everything turns.
  struct AxisSpring final : Controller {
    int a, b;
    AxisSpring(int a_in, int b_in) : a(a_in), b(b_in) {}
    void applyForces(World& w, double) override {
      std::vector<RigidBody>& bodies = w.bodies();
      const Eigen::Vector3d axis = bodies[a].q * Eigen::Vector3d::UnitZ();
      const double s = (bodies[b].x - bodies[a].x).dot(axis);
      const Eigen::Vector3d f = -200.0 * (s + 0.4) * axis;
      bodies[b].force += f;
      bodies[a].force -= f;
    }
  };
  world.addController(std::make_shared<AxisSpring>(a, b));
  double max_error = 0.0, min_slide = 1e9, max_slide = -1e9;
  const auto& knee = static_cast<const PrismaticJoint&>(*world.joints()[0]);
  for (int i = 0; i < 2000; ++i) {
    world.step();
    ASSERT_TRUE(world.ok()) << world.status();
    max_error = std::max(max_error, world.maxJointError());
    const double s = knee.slide(world.body(a), world.body(b));
    min_slide = std::min(min_slide, s);
    max_slide = std::max(max_slide, s);
  }
  EXPECT_LT(max_error, 1e-6) << "knee drift without stabilization over 2 s";
  EXPECT_GT(max_slide - min_slide, 0.02) << "the knee's free axis must stay free";
  std::printf("[ knee ] tumbling 2 s, no stabilization: max |C| = %.3g, slide range %.3f m\n", max_error,
              max_slide - min_slide);
}

TEST(HopperKnee, PhysicalNonsenseIsRefused) {
  HopperParams p;
  EXPECT_TRUE(validate(p).ok()) << validate(p).message();
  p.min_length = 0.9;
  EXPECT_NE(validate(p).message().find("min_length < rest_length < max_length"), std::string::npos)
      << validate(p).message();
  p = HopperParams{};
  p.body_mass = 0.0;
  EXPECT_NE(validate(p).message().find("hopper.body_mass"), std::string::npos) << validate(p).message();
  p = HopperParams{};
  p.position.z() = 0.5;
  EXPECT_NE(validate(p).message().find("below the ground"), std::string::npos) << validate(p).message();
  p = HopperParams{};
  p.script = {HopperCommandKey{.t = 5.0}, HopperCommandKey{.t = 2.0}};
  EXPECT_NE(validate(p).message().find("time order"), std::string::npos) << validate(p).message();

  PhysicsParams pp;
  World world(pp);
  p.script.clear();
  p.upper_length = 0.1;
  const auto hopper = Hopper::add(world, p);
  EXPECT_FALSE(hopper->built());
  EXPECT_FALSE(world.ok());
  EXPECT_NE(world.status().find("upper_length"), std::string::npos) << world.status();
}

}  // namespace
}  // namespace ponyhop

// A single rigid pendulum (one link of the chain builder on a fixed anchor) released from a
// large angle swings with the exact large-amplitude period of a physical pendulum:
//   T = 4 sqrt(I_pivot / (m g d)) K(k),  k = sin(theta0 / 2),
// K the complete elliptic integral of the first kind, K(k) = pi / (2 AGM(1, sqrt(1 - k^2))).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "physics/models/chain.h"

namespace ponyhop {
namespace {

double agm(double a, double b) {
  for (int i = 0; i < 60 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double m = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = m;
  }
  return a;
}

double ellipticK(double k) { return std::numbers::pi / (2.0 * agm(1.0, std::sqrt(1.0 - k * k))); }

TEST(PhysicsPendulum, EllipticKMatchesKnownValues) {
  EXPECT_NEAR(ellipticK(0.0), std::numbers::pi / 2.0, 1e-15);
  EXPECT_NEAR(ellipticK(std::sin(std::numbers::pi / 4.0)), 1.854074677301372, 1e-14);  // K(1/sqrt 2)
}

// Period measured from the zero crossings of the swing angle (where the angular acceleration
// vanishes, so linear interpolation between steps is accurate to O(h^3)).
double measuredPeriod(Integrator integrator, Stabilization stabilization, double theta0, double dt, double* expected) {
  PhysicsParams pp;
  pp.dt = dt;
  pp.integrator = integrator;
  pp.stabilization = stabilization;
  ChainParams cp;
  cp.links = 1;
  cp.length = 0.5;
  cp.mass = 1.0;
  cp.radius = 0.02;
  cp.direction = Eigen::Vector3d(std::sin(theta0), 0.0, -std::cos(theta0));
  AnchorParams ap;
  ChainWorld cw = makeChainWorld(pp, cp, ap);
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();

  const RigidBody& link = cw.world.body(cw.chain.links[0]);
  // Solid cylinder about a transverse axis through its end: m (3 r^2 + L^2) / 12 + m d^2
  // (computed here from the parameters, not taken from the body, so a wrong inertia shows).
  const double m = cp.mass, r = cp.radius, len = cp.length, d = 0.5 * len;
  const double i_pivot = m * (3.0 * r * r + len * len) / 12.0 + m * d * d;
  *expected = 4.0 * std::sqrt(i_pivot / (m * 9.81 * d)) * ellipticK(std::sin(theta0 / 2.0));

  const auto angle = [&] { return std::atan2(link.x.x(), -link.x.z()); };
  std::vector<double> crossings;
  double previous = angle();
  while (crossings.size() < 5 && cw.world.time() < 20.0) {
    const double t0 = cw.world.time();
    cw.world.step();
    const double now = angle();
    if ((previous > 0.0) != (now > 0.0)) crossings.push_back(t0 + dt * previous / (previous - now));
    previous = now;
  }
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();
  if (crossings.size() < 5) return 0.0;
  return (crossings[4] - crossings[0]) / 2.0;  // two full periods between crossings 1 and 5
}

TEST(PhysicsPendulum, LargeAmplitudePeriodRK4) {
  const double theta0 = 120.0 * std::numbers::pi / 180.0;
  double expected = 0.0;
  const double period = measuredPeriod(Integrator::RK4, Stabilization::Projection, theta0, 1e-3, &expected);
  // The small-angle period differs by 16%; the inertia's radius term alone by 0.1%.
  EXPECT_NEAR(period / expected, 1.0, 1e-6) << "period " << period << " s, exact " << expected << " s";
}

TEST(PhysicsPendulum, LargeAmplitudePeriodSymplecticEuler) {
  const double theta0 = 120.0 * std::numbers::pi / 180.0;
  double expected = 0.0;
  const double period = measuredPeriod(Integrator::SymplecticEuler, Stabilization::Projection, theta0, 1e-4, &expected);
  // First order, and post-stabilized symplectic Euler gains energy at a relative rate ~ h w^2
  // (the centripetal term is taken at the old state), so the swing grows and the period
  // lengthens: 0.25% after these two periods. A wrong inertia or gyroscopic term is off by more.
  EXPECT_NEAR(period / expected, 1.0, 5e-3) << "period " << period << " s, exact " << expected << " s";
}

}  // namespace
}  // namespace ponyhop

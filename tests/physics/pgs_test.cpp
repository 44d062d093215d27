// Projected Gauss-Seidel (physics/pgs.h) on small contact problems solved by hand: both normal
// rows active (a linear solve), one row that must separate (its impulse exactly zero, its
// velocity positive), a restitution target, and a contact with friction in the cone's interior
// (sticking) and on its rim (sliding, the friction at its bound mu p_n against the slip).
#include "physics/pgs.h"

#include <gtest/gtest.h>

namespace ponyhop {
namespace {

constexpr double kTol = 1e-12;

struct Solved {
  Eigen::VectorXd p, u;  // impulses and the velocities after them, u = u0 + D p
  int sweeps = 0;
};

Solved solve(const Eigen::MatrixXd& d, const Eigen::VectorXd& u0, const Eigen::VectorXd& target,
             const std::vector<std::pair<int, int>>& blocks, const std::vector<double>& mu) {
  Solved s;
  s.sweeps = projectedGaussSeidel(d, u0, target, blocks, mu, s.p).sweeps;
  s.u = u0 + d * s.p;
  return s;
}

// Two coupled normal rows, both approaching: both stay in contact, D p = -u0.
//   [2 1; 1 2] p = (3, 3)  ->  p = (1, 1), u = 0.
TEST(Pgs, TwoActiveContactsSolveTheLinearSystem) {
  Eigen::MatrixXd d(2, 2);
  d << 2, 1, 1, 2;
  const Solved s = solve(d, Eigen::Vector2d(-3, -3), Eigen::Vector2d::Zero(), {{0, 1}, {1, 1}}, {0.0, 0.0});
  EXPECT_NEAR(s.p(0), 1.0, kTol);
  EXPECT_NEAR(s.p(1), 1.0, kTol);
  EXPECT_NEAR(s.u(0), 0.0, kTol);
  EXPECT_NEAR(s.u(1), 0.0, kTol);
  EXPECT_LT(s.sweeps, 5000);
}

// The second contact separates. Both active would need p = (7/3, -5/3): a pull. The LCP's answer:
// p2 = 0 exactly, p1 = 3/2 (u1 = 0), and the second row moves apart at u2 = 1 + 3/2 = 5/2.
TEST(Pgs, SeparatingContactGetsNoImpulse) {
  Eigen::MatrixXd d(2, 2);
  d << 2, 1, 1, 2;
  const Solved s = solve(d, Eigen::Vector2d(-3, 1), Eigen::Vector2d::Zero(), {{0, 1}, {1, 1}}, {0.0, 0.0});
  EXPECT_NEAR(s.p(0), 1.5, kTol);
  EXPECT_EQ(s.p(1), 0.0);
  EXPECT_NEAR(s.u(0), 0.0, kTol);
  EXPECT_NEAR(s.u(1), 2.5, kTol);
}

// A restitution target: the normal velocity after the impulse is the target, 2 p - 1 = 1/2.
TEST(Pgs, NormalVelocityReachesItsTarget) {
  const Eigen::MatrixXd d = Eigen::MatrixXd::Constant(1, 1, 2.0);
  const Solved s = solve(d, Eigen::VectorXd::Constant(1, -1.0), Eigen::VectorXd::Constant(1, 0.5), {{0, 1}}, {0.0});
  EXPECT_NEAR(s.p(0), 0.75, kTol);
  EXPECT_NEAR(s.u(0), 0.5, kTol);
}

// Friction inside the cone: D = 1, mu = 0.5, approaching at 1 m/s with a slip (0.2, -0.1). The
// normal impulse is 1, and sticking needs |p_t| = |(-0.2, 0.1)| = 0.224 < mu p_n = 0.5: the slip
// is stopped.
TEST(Pgs, FrictionInsideTheConeSticks) {
  const Solved s =
      solve(Eigen::MatrixXd::Identity(3, 3), Eigen::Vector3d(-1, 0.2, -0.1), Eigen::Vector3d::Zero(), {{0, 3}}, {0.5});
  EXPECT_NEAR(s.p(0), 1.0, kTol);
  EXPECT_NEAR(s.p(1), -0.2, kTol);
  EXPECT_NEAR(s.p(2), 0.1, kTol);
  EXPECT_NEAR(s.u.norm(), 0.0, kTol);
}

// Friction at its bound: the same contact slipping at (2, 0). Sticking would need |p_t| = 2 >
// mu p_n = 0.5, so the friction sits on the rim, against the slip: p_t = (-0.5, 0), and the slip
// goes on at 2 - 0.5 = 1.5.
TEST(Pgs, FrictionBeyondTheConeSlidesAtItsBound) {
  const Solved s =
      solve(Eigen::MatrixXd::Identity(3, 3), Eigen::Vector3d(-1, 2, 0), Eigen::Vector3d::Zero(), {{0, 3}}, {0.5});
  EXPECT_NEAR(s.p(0), 1.0, kTol);
  EXPECT_NEAR(s.p(1), -0.5, kTol);
  EXPECT_NEAR(s.p(2), 0.0, kTol);
  EXPECT_NEAR(s.u(0), 0.0, kTol);
  EXPECT_NEAR(s.u(1), 1.5, kTol);
  EXPECT_NEAR(s.u(2), 0.0, kTol);
}

// A sliding contact solved as one block (exact_blocks) with a coupled 3 x 3 block, the way the
// contact stage solves it: the answer is on the rim against the slip (p_t = -mu p_n d, the slip
// after it along +d, the normal at its target), and it is the same from a cold start (the guess
// opposite the sticking impulse) as from a warm one pointing 60 deg off (the search near the
// last direction brackets the root from there).
TEST(Pgs, ExactBlockSlidesOnTheRimFromAnyStart) {
  Eigen::MatrixXd d(3, 3);
  d << 2.0, 0.3, -0.2, 0.3, 1.5, 0.4, -0.2, 0.4, 1.0;
  const Eigen::Vector3d u0(-1.0, 2.0, 1.0);
  const std::vector<std::pair<int, int>> blocks = {{0, 3}};
  PgsSettings settings{1e-12, 100, true, true};
  Eigen::VectorXd cold;
  projectedGaussSeidel(d, u0, Eigen::Vector3d::Zero(), blocks, {0.4}, cold, settings);
  Eigen::VectorXd warm = Eigen::Vector3d(0.5, -0.1, 0.17);
  projectedGaussSeidel(d, u0, Eigen::Vector3d::Zero(), blocks, {0.4}, warm, settings);
  for (const Eigen::VectorXd& p : {cold, warm}) {
    const Eigen::VectorXd u = u0 + d * p;
    EXPECT_NEAR(u(0), 0.0, 1e-9);
    EXPECT_GT(p(0), 0.0);
    EXPECT_NEAR(p.tail<2>().norm(), 0.4 * p(0), 1e-9);
    // The slip is along -p_t: their cross product vanishes and their dot product is negative.
    EXPECT_NEAR(p(1) * u(2) - p(2) * u(1), 0.0, 1e-7);
    EXPECT_LT(p.tail<2>().dot(u.tail<2>()), 0.0);
  }
  EXPECT_NEAR((cold - warm).norm(), 0.0, 1e-7);
}

}  // namespace
}  // namespace ponyhop

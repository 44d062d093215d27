// Adaptive dynamics (physics.adaptive_joints, physics.adaptive_tolerance; docs/SOLVERS.md): every
// joint active reproduces the full solver, a chain at rest holds no active joint, the lock keeps
// momentum and never adds energy, the error falls as the budget grows, bad budgets are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "common/physics_util.h"
#include "physics/featherstone.h"
#include "physics/models/chain.h"

namespace ponyhop {
namespace {

using testing::exactPhysics;

ChainWorld chainWorld(int links, int budget, double tolerance, const Eigen::Vector3d& direction) {
  PhysicsParams pp = exactPhysics(SolverKind::Featherstone);
  pp.adaptive_joints = budget;
  pp.adaptive_tolerance = tolerance;
  ChainParams cp;
  cp.links = links;
  cp.direction = direction;
  return makeChainWorld(pp, cp, AnchorParams{});
}

// The tip's path over `steps` steps of a chain released from horizontal.
std::vector<Eigen::Vector3d> tipPath(int links, int budget, double tolerance, int steps, int* max_active = nullptr) {
  ChainWorld cw = chainWorld(links, budget, tolerance, Eigen::Vector3d::UnitX());
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < steps && cw.world.ok(); ++i) {
    cw.world.step();
    out.push_back(cw.chain.tip(cw.world));
    if (max_active) *max_active = std::max(*max_active, cw.world.reduced()->activeJoints());
  }
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();
  return out;
}

double maxGap(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  EXPECT_EQ(a.size(), b.size());
  double gap = 0.0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) gap = std::max(gap, (a[i] - b[i]).norm());
  return gap;
}

// Budget = N is the plain step; budget = N with a tiny tolerance runs the adaptive machinery
// (scores, choice) with every joint active: the same arithmetic, so the same path.
TEST(PhysicsAdaptive, EveryJointActiveReproducesTheFullSolver) {
  const int steps = 96;
  const std::vector<Eigen::Vector3d> full = tipPath(6, 0, 0.0, steps);
  EXPECT_LT(maxGap(full, tipPath(6, 6, 0.0, steps)), 1e-12);
  int active = 0;
  EXPECT_LT(maxGap(full, tipPath(6, 6, 1e-30, steps, &active)), 1e-12);
  EXPECT_EQ(active, 6);
}

TEST(PhysicsAdaptive, AChainAtRestHasNoActiveJointAndStaysAtRest) {
  for (const auto& [budget, tolerance] : {std::pair{3, 0.0}, std::pair{0, 1e-9}}) {
    ChainWorld cw = chainWorld(6, budget, tolerance, -Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d tip0 = cw.chain.tip(cw.world);
    for (int i = 0; i < 48 && cw.world.ok(); ++i) {
      cw.world.step();
      EXPECT_EQ(cw.world.reduced()->activeJoints(), 0) << i;
    }
    ASSERT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_LT((cw.chain.tip(cw.world) - tip0).norm(), 1e-14);
    EXPECT_EQ(cw.world.kineticEnergy(), 0.0);
  }
}

// A free-floating hub with two 3-link chains (no gravity), stirred: every lock keeps the linear
// and angular momentum, never raises the kinetic energy, zeroes the locked joints' relative
// speeds and gives the free joints H_FF^-1 (H u)_F (checked against CRBA's H).
TEST(PhysicsAdaptive, TheLockKeepsMomentumAndNeverAddsEnergy) {
  PhysicsParams pp = exactPhysics(SolverKind::Featherstone);
  pp.gravity.setZero();
  World world(pp);
  RigidBody hub;
  hub.name = "hub";
  hub.mass = 0.5;
  hub.inertia = Eigen::Vector3d(2e-3, 3e-3, 4e-3);
  const int h = world.addDynamicBody(hub);
  ChainParams cp;
  cp.links = 3;
  cp.direction = Eigen::Vector3d(1, 0, -1);
  addChain(world, cp, h, Eigen::Vector3d(0.05, 0, 0));
  cp.direction = Eigen::Vector3d(-1, 0.5, -1);
  addChain(world, cp, h, Eigen::Vector3d(-0.05, 0, 0.01));
  world.evaluate();
  ASSERT_TRUE(world.ok()) << world.status();
  ArticulatedSystem& sys = *world.reduced();
  ASSERT_EQ(sys.jointCount(), 6);
  const auto momentum = [&] {
    Eigen::Matrix<double, 6, 1> out = Eigen::Matrix<double, 6, 1>::Zero();
    for (const RigidBody& b : world.bodies()) {
      out.head<3>() += b.mass * b.v;
      out.tail<3>() += b.x.cross(b.mass * b.v) + b.worldInertia() * b.w;
    }
    return out;
  };
  std::mt19937 rng(7u);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    for (RigidBody& b : world.bodies()) {
      b.v = Eigen::Vector3d(g(rng), g(rng), g(rng));
      b.w = 8.0 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    }
    sys.readState(world.bodies());   // joint speeds from the relative angular velocities
    sys.writeState(world.bodies());  // and the bodies' velocities from them
    const Eigen::Matrix<double, 6, 1> p0 = momentum();
    const double t0 = world.kineticEnergy();
    const Eigen::MatrixXd H = sys.massMatrix(world.bodies());
    const Eigen::VectorXd u0 = sys.velocities();
    std::vector<char> active(sys.nodeCount(), 1);
    for (size_t i = 1; i < active.size(); ++i) active[i] = (trial >> (i % 3)) & 1 ? 1 : 0;  // node 0: the hub
    sys.lock(world.bodies(), active);
    EXPECT_LT((momentum() - p0).norm(), 1e-12 * (1.0 + p0.norm())) << trial;
    EXPECT_LE(world.kineticEnergy(), t0 * (1.0 + 1e-14)) << trial;
    // The expected speeds: u_L = 0, u_F = H_FF^-1 (H u0)_F.
    std::vector<int> free;
    for (int i = 0; i < sys.nodeCount(); ++i) {
      const int dofs = i == 0 ? 6 : 3, first = i == 0 ? 0 : 3 + 3 * i;
      for (int k = 0; k < dofs && active[i]; ++k) free.push_back(first + k);
    }
    const Eigen::VectorXd hu = H * u0;
    Eigen::MatrixXd hff(free.size(), free.size());
    Eigen::VectorXd rhs(free.size());
    for (size_t a = 0; a < free.size(); ++a) {
      rhs(a) = hu(free[a]);
      for (size_t b = 0; b < free.size(); ++b) hff(a, b) = H(free[a], free[b]);
    }
    const Eigen::VectorXd uf = hff.llt().solve(rhs);
    Eigen::VectorXd expected = Eigen::VectorXd::Zero(u0.size());
    for (size_t a = 0; a < free.size(); ++a) expected(free[a]) = uf(a);
    EXPECT_LT((sys.velocities() - expected).norm(), 1e-10 * (1.0 + u0.norm())) << trial;
    EXPECT_LT(world.maxJointError(), 1e-12);
  }
}

// A 10-link chain released from horizontal, 0.15 s: the tip's distance from the full run falls
// as the budget grows (none at the full budget).
TEST(PhysicsAdaptive, ErrorFallsAsTheBudgetGrows) {
  const int steps = 144;
  const std::vector<Eigen::Vector3d> full = tipPath(10, 0, 0.0, steps);
  double last = 1e9;
  for (int budget : {2, 4, 7, 10}) {
    int active = 0;
    const double gap = maxGap(full, tipPath(10, budget, 0.0, steps, &active));
    EXPECT_LE(active, budget);
    EXPECT_LT(gap, last) << "budget " << budget;
    last = gap;
  }
  EXPECT_LT(last, 1e-12);
}

// Cost follows the budget: the step runs over one composite body per active joint, and a rigid
// stretch moves as one body (every rigid joint keeps its relative rotation to round-off) while
// the anchor shakes the hanging chain; the joints hold.
TEST(PhysicsAdaptive, TheStepRunsOverCompositesAndRigidStretchesMoveWhole) {
  PhysicsParams pp = exactPhysics(SolverKind::Featherstone);
  pp.adaptive_joints = 3;
  ChainParams cp;
  cp.links = 12;
  cp.direction = -Eigen::Vector3d::UnitZ();
  AnchorParams ap;
  ap.motion = AnchorMotion::Shake;
  ChainWorld cw = makeChainWorld(pp, cp, ap);
  const ArticulatedSystem* sys = nullptr;
  const auto relative = [&](int node) {
    const std::vector<RigidBody>& b = cw.world.bodies();
    return Eigen::Quaterniond(b[sys->nodeBody(node - 1)].q.conjugate() * b[sys->nodeBody(node)].q);
  };
  int held = 0;
  for (int i = 0; i < 96 && cw.world.ok(); ++i) {
    std::vector<Eigen::Quaterniond> before;
    std::vector<char> rigid_before;
    if (sys) {
      rigid_before = sys->activeNodes();
      for (int n = 1; n < sys->nodeCount(); ++n) before.push_back(relative(n));
    }
    cw.world.step();
    sys = cw.world.reduced();
    ASSERT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_LE(sys->steppedBodies(), 3) << i;
    EXPECT_LE(sys->activeJoints(), 3) << i;
    EXPECT_LT(cw.world.maxJointError(), 1e-12) << i;
    if (rigid_before.empty()) continue;
    const std::vector<char> active = sys->activeNodes();
    for (int n = 1; n < sys->nodeCount(); ++n) {
      if (rigid_before[n] || active[n]) continue;  // rigid through the step
      EXPECT_LT(relative(n).angularDistance(before[n - 1]), 1e-14) << "step " << i << ", joint " << n;
      ++held;
    }
  }
  EXPECT_GT(held, 0);
  // The rigid stretch below the active joints swings with them (it is not left behind).
  EXPECT_GT(cw.world.kineticEnergy(), 1e-4);
}

// The 12-link chain released from horizontal with budget 3: its top three joints move and the
// rest swings as one composite body (the set does not change here), so the energy is kept to the
// integrator's accuracy, as for any 3-joint pendulum: the composite's mass, centre, inertia and
// gravity load are its links'.
TEST(PhysicsAdaptive, ACompositeSwingsWithItsLinksMassAndInertia) {
  ChainWorld cw = chainWorld(12, 3, 0.0, Eigen::Vector3d::UnitX());
  const double e0 = cw.world.energy();
  std::vector<char> first;
  for (int i = 0; i < 96 && cw.world.ok(); ++i) {
    cw.world.step();
    if (first.empty()) first = cw.world.reduced()->activeNodes();
    ASSERT_EQ(cw.world.reduced()->activeNodes(), first) << i;
  }
  ASSERT_TRUE(cw.world.ok()) << cw.world.status();
  EXPECT_GT(cw.world.kineticEnergy(), 1e-3);
  EXPECT_LT(std::abs(cw.world.energy() - e0), 1e-9);
}

// The bench's chain (1 m, 0.2 kg, RK4 at 1/960 s with the automatic substeps of
// max_step_rotation), 64 links released from horizontal, budget 8: only joints at depths that are
// multiples of 64 / 8 = 8 are chosen, so no rigid stretch is shorter than 8 links, and once the
// whole chain moves it is the even split into 8 stretches of 8 links; the reduced chain then takes
// no more substeps than the full one and its energy rises no more. Choosing any joint (one-link
// composites between long ones) took 2.4 substeps per dt against the full chain's 1.7 and raised
// the energy 10x more than the full chain's error; choosing 8 of 16 candidates (stretches of 4 to
// 12 links) doubled the tip error of the long chains (docs/SOLVERS.md, "Why the candidates are spaced").
TEST(PhysicsAdaptive, SpacedCandidatesStepNoFinerThanTheFullChainAndAddNoEnergy) {
  struct Run {
    long substeps = 0;
    double rise = 0.0;
  };
  const auto run = [](int budget) {
    PhysicsParams pp;
    pp.dt = 1.0 / 960.0;
    pp.solver = SolverKind::Featherstone;
    pp.integrator = Integrator::RK4;
    pp.adaptive_joints = budget;
    ChainParams cp;
    cp.links = 64;
    cp.length = 1.0 / 64;
    cp.radius = 0.3 * cp.length;
    cp.mass = 0.2 / 64;
    cp.direction = Eigen::Vector3d::UnitX();
    ChainWorld cw = makeChainWorld(pp, cp, AnchorParams{});
    const double e0 = cw.world.energy();
    Run r;
    for (int i = 0; i < 480 && cw.world.ok(); ++i) {
      cw.world.step();
      r.substeps += cw.world.lastSubsteps();
      r.rise = std::max(r.rise, cw.world.energy() - e0);
      if (budget == 0) continue;
      const std::vector<char> active = cw.world.reduced()->activeNodes();
      // After the first 1/32 s every stretch moves: the even split.
      for (int n = 0; n < static_cast<int>(active.size()); ++n) {
        EXPECT_TRUE(!active[n] || n % 8 == 0) << n;
        if (i >= 30) {
          EXPECT_TRUE(active[n] || n % 8 != 0) << "step " << i << ", joint " << n;
        }
      }
    }
    EXPECT_TRUE(cw.world.ok()) << cw.world.status();
    return r;
  };
  const Run full = run(0), reduced = run(8);
  EXPECT_LE(reduced.substeps, full.substeps);
  EXPECT_LE(reduced.rise, full.rise);
}

// The bench's oracles (docs/bench/adaptive.md, "Oracles") choose through setChooser(): the
// shipped lock and composite step with the chooser's set. A chooser that names the even split
// moves the same joints as the shipped choice and follows its path; one that names every joint is
// the full solver; the set it names is the set that moves (free roots aside), every step.
TEST(PhysicsAdaptive, AChooserSetsTheActiveJoints) {
  const int steps = 96;
  const auto path = [&](int budget, const ArticulatedSystem::Chooser& chooser, std::vector<char>* seen = nullptr) {
    ChainWorld cw = chainWorld(12, budget, 0.0, Eigen::Vector3d::UnitX());
    cw.world.evaluate();
    cw.world.reduced()->setChooser(chooser);
    std::vector<Eigen::Vector3d> out;
    for (int i = 0; i < steps && cw.world.ok(); ++i) {
      cw.world.step();
      out.push_back(cw.chain.tip(cw.world));
      if (seen) {
        const std::vector<char> active = cw.world.reduced()->activeNodes();
        EXPECT_EQ(active, *seen) << "step " << i;
      }
    }
    EXPECT_TRUE(cw.world.ok()) << cw.world.status();
    return out;
  };
  const auto depths = [](std::vector<int> chosen) {
    return [chosen](double, const ArticulatedSystem& sys, const Eigen::VectorXd& udot, std::vector<char>& active) {
      EXPECT_EQ(udot.size(), sys.dofs());
      for (int i = 0; i < sys.nodeCount(); ++i) {
        for (int d : chosen) active[i] = active[i] || sys.nodeDepth(i) == d;
      }
    };
  };
  std::vector<char> even(12, 0);
  even[0] = even[4] = even[8] = 1;
  const std::vector<Eigen::Vector3d> shipped = path(3, nullptr), chosen = path(3, depths({0, 4, 8}), &even);
  EXPECT_LT(maxGap(shipped, chosen), 1e-9);
  std::vector<char> all(12, 1);
  EXPECT_LT(maxGap(tipPath(12, 0, 0.0, steps), path(11, depths({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}), &all)), 1e-12);
  std::vector<char> top(12, 0);
  top[0] = top[1] = top[2] = 1;
  path(3, depths({0, 1, 2}), &top);
}

TEST(PhysicsAdaptive, RefusesABudgetAboveTheJointsAndTheMultiplierSolvers) {
  ChainWorld cw = chainWorld(4, 5, 0.0, Eigen::Vector3d::UnitX());
  cw.world.step();
  ASSERT_FALSE(cw.world.ok());
  EXPECT_NE(cw.world.status().find("physics.adaptive_joints = 5 is more than the 4 joints"), std::string::npos)
      << cw.world.status();
  PhysicsParams pp = exactPhysics(SolverKind::Tree);
  pp.adaptive_tolerance = 1e-6;
  World tree(pp);
  ASSERT_FALSE(tree.ok());
  EXPECT_NE(tree.status().find("physics.adaptive_tolerance: adaptive dynamics runs on solver 'featherstone' only"),
            std::string::npos)
      << tree.status();
}

}  // namespace
}  // namespace ponyhop

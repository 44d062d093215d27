// RATTLE's order with velocity-dependent forces (physics/rattle.h): with the corrector of the
// second kick, damping, drag and the hopper's servos keep the method second order (the error
// falls ~4x when h halves); with it off (the classical explicit second kick at the predicted
// velocity) it is first order (~2x). Fixed substeps (no max_step_rotation, no tolerance), errors
// against a reference with 64x finer substeps at the same dt, so that the hopper thinks at the
// same times in every run and only the integration differs.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <vector>

#include "common/physics_util.h"
#include "physics/models/chain.h"
#include "physics/models/hopper.h"

namespace ponyhop {
namespace {

PhysicsParams fixedRattle(double dt, int substeps) {
  PhysicsParams pp;
  pp.integrator = Integrator::Rattle;
  pp.dt = dt;
  pp.substeps = substeps;
  pp.max_step_rotation = 0.0;
  pp.tolerance = 0.0;
  return pp;
}

// How far two poses of the same bodies are apart: centres, plus the turn times 0.1 m (a point at
// a typical distance from the centre).
double poseDistance(const std::vector<BodyState>& a, const std::vector<BodyState>& b) {
  double d = 0.0;
  for (size_t i = 0; i < a.size(); ++i)
    d = std::max(d, (a[i].x - b[i].x).norm() + 0.1 * rotationVector(a[i].q * b[i].q.conjugate()).norm());
  return d;
}

std::vector<BodyState> poses(const World& world) {
  std::vector<BodyState> out;
  for (const RigidBody& b : world.bodies())
    if (b.isDynamic()) out.push_back(b.state());
  return out;
}

struct Ratios {
  double e1, e2, e3;
  double first() const { return e1 / e2; }
  double second() const { return e2 / e3; }
};

// Errors at substeps n, 2n, 4n against 64n, the run given by `poseAfter(substeps, corrector)`.
Ratios errors(const std::function<std::vector<BodyState>(int, bool)>& poseAfter, int n, bool corrector) {
  const std::vector<BodyState> ref = poseAfter(64 * n, true);
  return {poseDistance(poseAfter(n, corrector), ref), poseDistance(poseAfter(2 * n, corrector), ref),
          poseDistance(poseAfter(4 * n, corrector), ref)};
}

// A 4-link chain with joint damping and air drag, fixed anchor, released from horizontal.
std::vector<BodyState> dampedChain(int substeps, bool corrector, double seconds) {
  ChainParams cp;
  cp.links = 4;
  cp.damping = 2e-4;  // N m s/rad: the swing loses a good part of its energy within the run
  cp.damping_tip = 1.0;
  cp.drag = 0.5;  // N s/m per metre
  ChainWorld cw = makeChainWorld(fixedRattle(1.0 / 240.0, substeps), cp, AnchorParams{});
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();
  cw.world.setRattleCorrector(corrector);
  testing::runFor(cw.world, seconds);
  return poses(cw.world);
}

// Prints the errors and checks the order: ratios ~4 per halving with the corrector; with the
// classical second kick first order (~2), so the corrector is what makes the difference.
void expectSecondOrderOnlyWithTheCorrector(const char* what, const Ratios& with, const Ratios& without) {
  std::printf(
      "%s:\n"
      "  corrector on:  %.3e %.3e %.3e m (ratios %.2f %.2f)\n"
      "  corrector off: %.3e %.3e %.3e m (ratios %.2f %.2f)\n",
      what, with.e1, with.e2, with.e3, with.first(), with.second(), without.e1, without.e2, without.e3, without.first(),
      without.second());
  EXPECT_GT(with.first(), 3.2) << what;
  EXPECT_GT(with.second(), 3.2) << what;
  EXPECT_LT(with.first(), 5.0) << what;
  EXPECT_LT(with.second(), 5.0) << what;
  EXPECT_LT(without.first(), 2.8) << what;
  EXPECT_LT(without.second(), 2.8) << what;
  EXPECT_GT(without.second(), 1.5) << what;
  EXPECT_LT(with.e3, 0.5 * without.e3) << what;
}

TEST(RattleOrder, DampedChainIsSecondOrderWithTheCorrector) {
  const auto run = [](int substeps, bool corrector) { return dampedChain(substeps, corrector, 0.25); };
  expectSecondOrderOnlyWithTheCorrector("damped chain, error at 0.25 s for h = dt, dt/2, dt/4 (dt = 1/240 s)",
                                        errors(run, 1, true), errors(run, 1, false));
}

// Every body's x, q, v, w bit for bit.
void expectSameStates(const std::vector<BodyState>& a, const std::vector<BodyState>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].x, b[i].x) << i;
    EXPECT_EQ(a[i].v, b[i].v) << i;
    EXPECT_EQ(a[i].w, b[i].w) << i;
    EXPECT_EQ(a[i].q.coeffs(), b[i].q.coeffs()) << i;
  }
}

// Without velocity-dependent forces the corrector never runs: the step is bit for bit the one
// with it switched off.
TEST(RattleOrder, UndampedChainIsUntouchedByTheCorrector) {
  const auto tip = [](bool corrector) {
    ChainParams cp;
    cp.links = 4;
    cp.stiffness = 0.01;  // a bending spring: position-only
    ChainWorld cw = makeChainWorld(fixedRattle(1.0 / 240.0, 1), cp, AnchorParams{});
    cw.world.setRattleCorrector(corrector);
    testing::runFor(cw.world, 0.5);
    return poses(cw.world);
  };
  expectSameStates(tip(true), tip(false));
}

// The chord iteration starts from the factorization of A(q_n) that the last step's velocity solve
// left in the solver, when nothing has factored or moved since, else it factors A(q_n) itself:
// the same matrix, so the same steps bit for bit. Against an undisturbed world: one whose solver
// is refactored between steps (lambda() on demand: the acceleration-level solve at the same
// positions), and one that looks a step ahead and restores, so that the solver holds A at
// positions the world is no longer at (a reuse then would change the round-off).
TEST(RattleOrder, TheChordMatrixLeftByTheLastStepChangesNothing) {
  for (SolverKind solver : {SolverKind::Tree, SolverKind::Dense}) {
    const auto run = [&](int disturb) {
      PhysicsParams pp = fixedRattle(1.0 / 240.0, 1);
      pp.max_step_rotation = 2.0;  // with the default step control: splits, rejected steps
      pp.solver = solver;
      ChainParams cp;
      cp.links = 6;
      ChainWorld cw = makeChainWorld(pp, cp, AnchorParams{});
      for (int i = 0; i < 240 && cw.world.ok(); ++i) {
        cw.world.step();
        if (disturb == 1) (void)cw.world.lambda();
        if (disturb == 2) {
          const World::SavedState saved = cw.world.saveState();
          cw.world.step();
          cw.world.restoreState(saved);
        }
      }
      EXPECT_TRUE(cw.world.ok()) << cw.world.status();
      return poses(cw.world);
    };
    const std::vector<BodyState> quiet = run(0);
    expectSameStates(quiet, run(1));
    expectSameStates(quiet, run(2));
  }
}

// The hopper in flight: dropped from 3 m above its standing height, it falls for ~0.8 s; the
// leg spring (with its damping) and the hip servos (placement, twist: stiffness and damping) act
// all the way. 0.3 s measured, the toe far above the ground throughout.
std::vector<BodyState> hopperInFlight(int substeps, bool corrector) {
  HopperParams hp;
  testing::HopperWorld run(hp, fixedRattle(1e-3, substeps));
  World& world = run.world;
  EXPECT_TRUE(world.ok()) << world.status();
  for (RigidBody& b : world.bodies()) {
    if (!b.isDynamic()) continue;
    b.x.z() += 3.0;
    b.v = Eigen::Vector3d(0.8, -0.3, 0.0);  // a sideways throw: the placement servos work
  }
  world.setRattleCorrector(corrector);
  for (int i = 0; i < 300 && world.ok(); ++i) {
    world.step();
    EXPECT_FALSE(run.hopper->inContact()) << "the measured interval must be flight";
  }
  EXPECT_TRUE(world.ok()) << world.status();
  EXPECT_GT(run.hopper->footPoint(world).z(), 0.5);
  return poses(world);
}

TEST(RattleOrder, HopperInFlightIsSecondOrderWithTheCorrector) {
  expectSecondOrderOnlyWithTheCorrector("hopper in flight, error at 0.3 s for h = dt, dt/2, dt/4 (dt = 1 ms)",
                                        errors(hopperInFlight, 1, true), errors(hopperInFlight, 1, false));
}

}  // namespace
}  // namespace ponyhop

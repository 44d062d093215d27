// The canonical chain (8 identical links of 5 cm, released horizontally from a fixed anchor)
// against what is known: energy conservation, convergence order, joint drift under projection,
// workless joints, Galilean invariance, Kelvin's minimum-energy start.
#include "physics/models/chain.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "common/physics_util.h"
#include "physics/spherical_joint.h"
#include "physics/stability_monitor.h"

namespace ponyhop {
namespace {

using testing::expectRatio;
using testing::linkPositions;
using testing::maxDistance;
using testing::maxEnergyDrift;
using testing::runFor;

ChainWorld chainWorld(Integrator integrator, Stabilization stabilization, double dt, int links = 8,
                      AnchorParams anchor = {}) {
  PhysicsParams pp;
  pp.dt = dt;
  pp.integrator = integrator;
  pp.stabilization = stabilization;
  pp.max_step_rotation = 0.0;  // exactly dt per step (these tests measure the fixed-step methods)
  ChainParams cp;
  cp.links = links;
  ChainWorld cw = makeChainWorld(pp, cp, anchor);
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();
  return cw;
}

TEST(PhysicsChain, ReleasedChainStartsWithPositiveEnergyAndHangingChainHasNone) {
  ChainWorld released = chainWorld(Integrator::RK4, Stabilization::Projection, 1.0 / 240.0);
  // E0 = sum m g (i + 1/2) L = 0.02 * 9.81 * 0.05 * 32 for 8 links.
  EXPECT_NEAR(released.world.energy(), 0.02 * 9.81 * 0.05 * 32.0, 1e-12);
  PhysicsParams pp;
  ChainParams hanging;
  hanging.direction = Eigen::Vector3d(0.0, 0.0, -1.0);
  ChainWorld rest = makeChainWorld(pp, hanging, AnchorParams{});
  EXPECT_NEAR(rest.world.energy(), 0.0, 1e-15);
  EXPECT_NEAR(rest.chain.tip(rest.world).z(), -0.4, 1e-15);
}

// RK4 at dt = 1e-4 over 0.5 s (through the first whip of the tip): |E - E0| < 1e-9 J against
// E0 = 0.314 J (measured: 6e-12 J).
TEST(PhysicsChain, RK4ConservesEnergyAtSmallStep) {
  ChainWorld cw = chainWorld(Integrator::RK4, Stabilization::Projection, 1e-4);
  const double e0 = cw.world.energy();
  EXPECT_LT(maxEnergyDrift(cw.world, 5000), 1e-9) << "E0 = " << e0 << " J";
}

// Errors in the link positions at t = 0.2 s against RK4 at dt/32. The released chain is
// chaotic, so only this early horizon means anything.
double positionError(Integrator integrator, double dt, const std::vector<Eigen::Vector3d>& reference) {
  ChainWorld cw = chainWorld(integrator, Stabilization::None, dt);
  runFor(cw.world, 0.2);
  return maxDistance(linkPositions(cw), reference);
}

TEST(PhysicsChain, ConvergenceOrderWhenDtHalves) {
  ChainWorld ref = chainWorld(Integrator::RK4, Stabilization::None, 1.0 / 15360.0);
  runFor(ref.world, 0.2);
  const std::vector<Eigen::Vector3d> reference = linkPositions(ref);

  const double rk1 = positionError(Integrator::RK4, 1.0 / 240.0, reference);
  const double rk2 = positionError(Integrator::RK4, 1.0 / 480.0, reference);
  const double rk3 = positionError(Integrator::RK4, 1.0 / 960.0, reference);
  expectRatio(rk1, rk2, 11.0, 22.0);  // 2^4 = 16
  expectRatio(rk2, rk3, 11.0, 22.0);

  const double se1 = positionError(Integrator::SymplecticEuler, 1.0 / 960.0, reference);
  const double se2 = positionError(Integrator::SymplecticEuler, 1.0 / 1920.0, reference);
  const double se3 = positionError(Integrator::SymplecticEuler, 1.0 / 3840.0, reference);
  expectRatio(se1, se2, 1.6, 2.6);  // 2^1 = 2
  expectRatio(se2, se3, 1.6, 2.6);
}

// Post-stabilization keeps every joint closed to round-off, with a shaking anchor, for both
// integrators; without it the joints drift apart: slowly with RK4 (the anchor's known
// acceleration enters the right-hand side; without it the drift would be centimetres), fast
// with symplectic Euler.
TEST(PhysicsChain, ProjectionKeepsJointsClosed) {
  AnchorParams shake;
  shake.motion = AnchorMotion::Shake;
  for (Integrator integrator : {Integrator::RK4, Integrator::SymplecticEuler}) {
    ChainWorld cw = chainWorld(integrator, Stabilization::Projection, 1.0 / 960.0, 8, shake);
    double worst = 0.0;
    for (int i = 0; i < 480 && cw.world.ok(); ++i) {
      cw.world.step();
      worst = std::max(worst, cw.world.maxJointError());
    }
    EXPECT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_LT(worst, 1e-9) << enumName(integrator);

    ChainWorld drifting = chainWorld(integrator, Stabilization::None, 1.0 / 960.0, 8, shake);
    runFor(drifting.world, 0.5);
    EXPECT_GT(drifting.world.maxJointError(), 1e-9) << enumName(integrator) << ": drift is too small to tell";
    if (integrator == Integrator::RK4) {
      EXPECT_LT(drifting.world.maxJointError(), 1e-5);  // measured 1.3e-6
    }
  }
}

// World::maxJointError() (joint by joint, nothing allocated: `sim --csv` reads it for its rows) is
// exactly the stacked system's max |C|, on a chain drifting without stabilization.
TEST(PhysicsChain, MaxJointErrorIsTheStackedSystemsBitForBit) {
  ChainWorld cw = chainWorld(Integrator::SymplecticEuler, Stabilization::None, 1.0 / 240.0);
  for (int i = 0; i < 24; ++i) {
    cw.world.step();
    ConstraintSystem system;
    system.evaluate(cw.world.bodies(), cw.world.joints());
    ASSERT_GT(system.maxError(), 0.0);
    EXPECT_EQ(cw.world.maxJointError(), system.maxError()) << "step " << i;
  }
}

// F_c = J^T lambda does no work when J v = 0 (fixed anchor): sum F_c.v + t_c.w ~ 0 relative to
// sum |F_c||v| + |t_c||w|. With a shaking anchor the joint to it does work (a positive check
// that the measurement can see power).
double relativeConstraintPower(ChainWorld& cw, double seconds, double* worst_abs = nullptr) {
  double worst = 0.0;
  const int steps = static_cast<int>(std::lround(seconds / cw.world.params().dt));
  for (int i = 0; i < steps && cw.world.ok(); ++i) {
    cw.world.step();
    cw.world.evaluate();  // forces at the state just reached
    double scale = 0.0;
    for (int id : cw.chain.links) {
      const RigidBody& b = cw.world.body(id);
      scale += b.constraint_force.norm() * b.v.norm() + b.constraint_torque.norm() * b.w.norm();
    }
    worst = std::max(worst, std::abs(cw.world.constraintPower()) / scale);
  }
  if (worst_abs) *worst_abs = worst;
  return worst;
}

TEST(PhysicsChain, ConstraintForcesDoNoWork) {
  ChainWorld fixed = chainWorld(Integrator::RK4, Stabilization::Projection, 1.0 / 960.0);
  EXPECT_LT(relativeConstraintPower(fixed, 0.5), 1e-10);
  // Without projection J v = 0 holds only as well as RK4 integrates it (measured 1.5e-10).
  ChainWorld unstabilized = chainWorld(Integrator::RK4, Stabilization::None, 1e-4);
  EXPECT_LT(relativeConstraintPower(unstabilized, 0.3), 1e-8);

  AnchorParams shake;
  shake.motion = AnchorMotion::Shake;
  ChainWorld shaken = chainWorld(Integrator::RK4, Stabilization::Projection, 1.0 / 960.0, 8, shake);
  EXPECT_GT(relativeConstraintPower(shaken, 0.5), 1e-2);
}

// Galilean invariance: a chain on an anchor moving at constant velocity V (starting with the
// anchor's velocity) moves exactly as the fixed-anchor chain carried along by V t.
TEST(PhysicsChain, ConstantVelocityAnchorIsGalileanShift) {
  AnchorParams moving;
  moving.motion = AnchorMotion::ConstantVelocity;
  moving.velocity = Eigen::Vector3d(0.7, -0.4, 0.3);
  for (Stabilization st : {Stabilization::Projection, Stabilization::Baumgarte}) {
    ChainWorld a = chainWorld(Integrator::RK4, st, 1.0 / 480.0);
    ChainWorld b = chainWorld(Integrator::RK4, st, 1.0 / 480.0, 8, moving);
    double worst = 0.0;
    for (int i = 0; i < 240 && a.world.ok() && b.world.ok(); ++i) {
      a.world.step();
      b.world.step();
      for (size_t k = 0; k < a.chain.links.size(); ++k) {
        const RigidBody& la = a.world.body(a.chain.links[k]);
        const RigidBody& lb = b.world.body(b.chain.links[k]);
        worst = std::max(worst, (lb.x - (la.x + moving.velocity * a.world.time())).norm());
        worst = std::max(worst, (lb.v - (la.v + moving.velocity)).norm() * 1e-2);
      }
    }
    EXPECT_TRUE(a.world.ok() && b.world.ok());
    EXPECT_LT(worst, 1e-9) << enumName(st);
  }
}

// Kelvin: the shaking anchor moves at t = 0 while the chain is at rest; the chain starts with
// the least-kinetic-energy velocities that satisfy J v = -J_k v_k.
TEST(PhysicsChain, KelvinInitialVelocities) {
  AnchorParams shake;
  shake.motion = AnchorMotion::Shake;
  ChainWorld cw = chainWorld(Integrator::RK4, Stabilization::Projection, 1.0 / 240.0, 8, shake);
  World& world = cw.world;

  ConstraintSystem system;
  system.evaluate(world.bodies(), world.joints());
  std::vector<Vector6d> vel(world.bodyCount());
  for (int i = 0; i < world.bodyCount(); ++i) vel[i] << world.body(i).v, world.body(i).w;
  EXPECT_LT(system.times(vel).lpNorm<Eigen::Infinity>(), 1e-12);  // J v + J_k v_k = 0
  EXPECT_GT(world.body(cw.anchor).v.norm(), 0.5);                 // the anchor does move

  const double ke = world.kineticEnergy();
  EXPECT_GT(ke, 0.0);
  std::vector<RigidBody> kelvin = world.bodies();
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    for (int id : cw.chain.links) {
      world.body(id).v = kelvin[id].v + Eigen::Vector3d(n(rng), n(rng), n(rng));
      world.body(id).w = kelvin[id].w + 10.0 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    }
    world.projectVelocities();  // another consistent velocity field (same anchor velocity)
    EXPECT_GT(world.kineticEnergy(), ke * (1.0 + 1e-9)) << "trial " << trial;
    for (int id : cw.chain.links) {
      world.body(id).v = kelvin[id].v;
      world.body(id).w = kelvin[id].w;
    }
  }
}

// The spherical joint's J and J'q' against finite differences of C along a motion with
// constant velocities (then C' = J q' and C'' = J'q').
TEST(PhysicsChain, SphericalJointDerivativesMatchFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto vec = [&] { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  for (int trial = 0; trial < 10; ++trial) {
    RigidBody a, b;
    a.x = vec();
    b.x = vec();
    a.q = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized());
    b.q = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized());
    a.v = vec();
    b.v = vec();
    a.w = 3.0 * vec();
    b.w = 3.0 * vec();
    const SphericalJoint joint(0, vec(), 1, vec());
    const auto at = [&](double t) {
      RigidBody at_a = a, at_b = b;
      at_a.x += t * a.v;
      at_b.x += t * b.v;
      at_a.q = quaternionFromRotationVector(t * a.w) * a.q;
      at_b.q = quaternionFromRotationVector(t * b.w) * b.q;
      return joint.rowsAt(at_a, at_b);
    };
    const ConstraintRows r0 = at(0.0);
    const double h = 1e-4;
    const Eigen::Vector3d dc = (at(h).C - at(-h).C) / (2.0 * h);
    const Eigen::Vector3d ddc = (at(h).C - 2.0 * r0.C + at(-h).C) / (h * h);
    Vector6d qa, qb;
    qa << a.v, a.w;
    qb << b.v, b.w;
    EXPECT_LT((r0.ja * qa + r0.jb * qb - dc).norm(), 1e-6);
    EXPECT_LT((r0.bias - ddc).norm(), 1e-4 * (1.0 + ddc.norm()));
  }
}

// The stage clock (physics/stage_times.h) off: the same steps, the stages still counted, no time
// charged; on again: time charged from then on.
TEST(PhysicsChain, StageTimingCanBeSwitchedOff) {
  ChainWorld timed = chainWorld(Integrator::SymplecticEuler, Stabilization::None, 1.0 / 1920.0);
  ChainWorld untimed = chainWorld(Integrator::SymplecticEuler, Stabilization::None, 1.0 / 1920.0);
  untimed.world.setStageTiming(false);
  for (int i = 0; i < 50; ++i) {
    timed.world.step();
    untimed.world.step();
  }
  ASSERT_TRUE(timed.world.ok() && untimed.world.ok());
  for (int i = 0; i < untimed.world.bodyCount(); ++i) {
    EXPECT_EQ(timed.world.body(i).x, untimed.world.body(i).x);
    EXPECT_EQ(timed.world.body(i).v, untimed.world.body(i).v);
  }
  const StageTimes& off = untimed.world.stageTimes();
  EXPECT_EQ(off.total(), 0.0);
  EXPECT_EQ(off.calls, timed.world.stageTimes().calls);
  EXPECT_EQ(off.calls[static_cast<int>(Stage::JointForces)], 50);
  EXPECT_GT(timed.world.stageTimes()[Stage::JointForces], 0.0);
  untimed.world.setStageTiming(true);
  for (int i = 0; i < 50; ++i) untimed.world.step();
  EXPECT_GT(untimed.world.stageTimes()[Stage::JointForces], 0.0);
}

// On the thread CPU source a stage is charged the CPU it used, not the time it waited: a stage that
// sleeps 20 ms costs next to nothing (on wall time it would cost the 20 ms). A stage outside the
// mask is counted and not timed.
TEST(PhysicsChain, StageClockOnThreadCpuChargesNoSleep) {
  StageClock clock;
  clock.setSource(StageClock::Source::ThreadCpu, StageClock::bit(Stage::Contact));
  {
    const auto timed = clock.time(Stage::Contact);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  {
    const auto untimed = clock.time(Stage::Integrate);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const StageTimes& t = clock.times();
  EXPECT_EQ(t.calls[static_cast<int>(Stage::Contact)], 1);
  EXPECT_EQ(t.calls[static_cast<int>(Stage::Integrate)], 1);
  EXPECT_GE(t[Stage::Contact], 0.0);
  EXPECT_LT(t[Stage::Contact], 0.005);
  EXPECT_EQ(t[Stage::Integrate], 0.0);
}

// The stability monitor reads the bodies in place (symplectic Euler) or a gathered copy (the other
// explicit methods): the same estimates from the same states.
TEST(PhysicsChain, StabilityMonitorReadsBodiesAsAGatheredState) {
  ChainWorld cw = chainWorld(Integrator::SymplecticEuler, Stabilization::None, 1.0 / 240.0);
  StabilityMonitor in_place, gathered;
  std::vector<int> dynamic;
  for (int i = 0; i < cw.world.bodyCount(); ++i)
    if (cw.world.body(i).isDynamic()) dynamic.push_back(i);
  for (int step = 0; step < 40; ++step) {
    cw.world.evaluate();
    State y;
    Accelerations f;
    for (int i : dynamic) {
      y.push_back(cw.world.body(i).state());
      f.push_back({cw.world.body(i).a, cw.world.body(i).alpha});
    }
    EXPECT_EQ(in_place.observe(1.0 / 240.0, cw.world.bodies(), dynamic, 2.0), gathered.observe(1.0 / 240.0, y, f, 2.0));
    EXPECT_EQ(in_place.hRho(), gathered.hRho());
    EXPECT_EQ(in_place.growth(), gathered.growth());
    cw.world.step();
  }
  EXPECT_GT(gathered.hRho(), 0.0);
}

// The monitor's own atan2 (its turn angles) agrees with libm's within 4 ulp over the whole first
// quadrant: near the axes, at and between its table's grid points t = k / 64, and beyond 1.
TEST(PhysicsChain, StabilityMonitorAtanAgreesWithLibm) {
  double worst = 0.0, worst_t = 0.0;
  const auto check = [&](double y, double x) {
    const double want = std::atan2(y, x), got = atan2NonNegative(y, x);
    const double ulps = std::abs(got - want) / (std::numeric_limits<double>::epsilon() * std::max(want, 1e-300));
    if (ulps > worst) {
      worst = ulps;
      worst_t = y / x;
    }
  };
  for (int i = 0; i <= 256000; ++i) {
    const double t = i / 128000.0;  // 0 ... 2, through every grid point and half-way between
    check(t, 1.0);
    check(1.0, t);         // y / x from 1/2 to infinity (x = 0: pi / 2)
    check(t * 1e-3, 1.0);  // small turns
    check(3.7 * t, 3.7);   // scaled
  }
  for (double t = 1.0 / 128.0; t < 1.0; t += 1.0 / 64.0) check(std::nextafter(t, 2.0), 1.0);  // at the splits
  EXPECT_LT(worst, 4.0) << "at y / x = " << worst_t;
  EXPECT_EQ(atan2NonNegative(0.0, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(atan2NonNegative(1.0, 0.0), 0.5 * std::numbers::pi);
  EXPECT_TRUE(std::isnan(atan2NonNegative(std::nan(""), 1.0)));
}

}  // namespace
}  // namespace ponyhop

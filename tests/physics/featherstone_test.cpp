// Reduced coordinates (physics.solver = featherstone): ABA, RNEA and CRBA checked against each
// other and against the multiplier solvers; joints held exactly; plain messages for what it
// cannot express.
#include "physics/featherstone.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>
#include <vector>

#include "common/physics_util.h"
#include "physics/models/chain.h"
#include "physics/prismatic_joint.h"
#include "physics/spherical_joint.h"

namespace ponyhop {
namespace {

using testing::exactPhysics;
using testing::joinTips;

AnchorParams anchor(AnchorMotion m) {
  AnchorParams a;
  a.motion = m;
  return a;
}

// The test systems, built the same way for any solver:
//   0: the canonical chain (8 links) on a shaking anchor;
//   1: a free-floating hub (floating base) with two chains with bending springs and damping;
//   2: a hopper-like leg: a body on the world by a spherical joint, a prismatic slider below it
//      with a foot, and a chain on the foot;
//   3: closed loops: two chains from the world joined at their tips (a loop through the world),
//      and a free hub with two chains joined at their tips (a loop of dynamic bodies).
World makeSystem(int which, const PhysicsParams& pp) {
  if (which == 0) {
    ChainParams cp;
    cp.links = 8;
    ChainWorld cw = makeChainWorld(pp, cp, anchor(AnchorMotion::Shake));
    return std::move(cw.world);
  }
  World world(pp);
  RigidBody hub;
  hub.name = "hub";
  hub.mass = 0.5;
  hub.inertia = Eigen::Vector3d(2e-3, 3e-3, 4e-3);
  hub.x = Eigen::Vector3d(0.1, 0.2, 1.0);
  hub.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  const int h = world.addDynamicBody(hub);
  ChainParams cp;
  cp.links = 4;
  if (which == 3) {
    cp.direction = Eigen::Vector3d(1, 0, -0.2);
    const Chain a = addChain(world, cp, kWorldBody, Eigen::Vector3d(0, 0, 0));
    cp.direction = Eigen::Vector3d(1, 0, 0.2);
    joinTips(world, a, addChain(world, cp, kWorldBody, Eigen::Vector3d(0, 0, -0.08)));
    cp.links = 3;
    cp.direction = Eigen::Vector3d(1, 0, -1);
    const Chain c = addChain(world, cp, h, Eigen::Vector3d(0.05, 0, 0));
    cp.direction = Eigen::Vector3d(1, 0.3, -0.9);
    joinTips(world, c, addChain(world, cp, h, Eigen::Vector3d(0.03, 0.02, -0.04)));
    return world;
  }
  if (which == 1) {
    cp.direction = Eigen::Vector3d(1, 0, -1);
    cp.stiffness = 0.02;
    cp.damping = 1e-4;
    addChain(world, cp, h, Eigen::Vector3d(0.05, 0, 0));
    cp.direction = Eigen::Vector3d(-1, 0.5, -1);
    addChain(world, cp, h, Eigen::Vector3d(-0.05, 0, 0.01));
    return world;
  }
  world.addJoint(
      std::make_unique<SphericalJoint>(kWorldBody, Eigen::Vector3d(0.1, 0.2, 1.1), h, Eigen::Vector3d(0, 0, 0.1)));
  RigidBody foot;
  foot.name = "foot";
  foot.mass = 0.2;
  foot.inertia = Eigen::Vector3d(1e-3, 1e-3, 2e-4);
  const Eigen::Quaterniond frame(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()));
  foot.q = hub.q * frame;
  foot.x = hub.x + hub.q * (frame * Eigen::Vector3d(0, 0, -0.2));
  const int f = world.addDynamicBody(foot);
  world.addJoint(std::make_unique<PrismaticJoint>(h, Eigen::Vector3d::Zero(), frame, f, Eigen::Vector3d(0, 0, 0.2),
                                                  Eigen::Quaterniond::Identity()));
  cp.direction = Eigen::Vector3d(0, 1, -1);
  addChain(world, cp, f, Eigen::Vector3d(0, 0, -0.05));
  return world;
}
World makeSystem(int which, SolverKind solver) { return makeSystem(which, exactPhysics(solver)); }

// Random joint-consistent velocities (Kelvin projection of random ones).
void stirVelocities(World& world, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  for (RigidBody& b : world.bodies()) {
    if (!b.isDynamic()) continue;
    b.v += Eigen::Vector3d(n(rng), n(rng), n(rng));
    b.w += 8.0 * Eigen::Vector3d(n(rng), n(rng), n(rng));
  }
  world.projectVelocities();
}

TEST(PhysicsFeatherstone, AbaAccelerationsEqualTheMultiplierSolvers) {
  for (int which : {0, 1, 2, 3}) {
    World dense = makeSystem(which, SolverKind::Dense);
    World feather = makeSystem(which, SolverKind::Featherstone);
    ASSERT_TRUE(dense.ok()) << dense.status();
    ASSERT_TRUE(feather.ok()) << feather.status();
    stirVelocities(dense, 17u + which);
    feather.bodies() = dense.bodies();  // the same state at t = 0 (the reduced state is read from it)
    dense.evaluate();
    feather.evaluate();
    ASSERT_TRUE(feather.ok()) << feather.status();
    double scale = 0.0, gap = 0.0;
    for (int i = 0; i < dense.bodyCount(); ++i) {
      const RigidBody &d = dense.body(i), &f = feather.body(i);
      if (!d.isDynamic()) continue;
      scale = std::max({scale, d.a.norm(), d.alpha.norm()});
      gap = std::max({gap, (d.a - f.a).norm(), (d.alpha - f.alpha).norm()});
      // The constraint forces ABA reports equal J^T lambda.
      EXPECT_LT((d.constraint_force - f.constraint_force).norm(), 1e-8 * (1.0 + d.constraint_force.norm())) << i;
      EXPECT_LT((d.constraint_torque - f.constraint_torque).norm(), 1e-8 * (1.0 + d.constraint_torque.norm())) << i;
    }
    EXPECT_GT(scale, 1.0);
    EXPECT_LT(gap, 1e-9 * scale) << "system " << which;
  }
}

// After a step the bodies' accelerations, applied forces and constraint forces come from one
// evaluation (RK4: the last stage; the stages before it leave the constraint forces out), so
// Newton holds body by body: m a = f + f_c.
TEST(PhysicsFeatherstone, StepLeavesForcesOfOneEvaluation) {
  for (Integrator integrator : {Integrator::RK4, Integrator::SymplecticEuler}) {
    PhysicsParams pp = exactPhysics(SolverKind::Featherstone, 1.0 / 240.0);
    pp.integrator = integrator;
    pp.stabilization = Stabilization::None;
    World world = makeSystem(0, pp);
    ASSERT_TRUE(world.ok()) << world.status();
    stirVelocities(world, 5u);
    for (int s = 0; s < 5; ++s) {
      world.step();
      ASSERT_TRUE(world.ok()) << world.status();
      for (int i = 0; i < world.bodyCount(); ++i) {
        const RigidBody& b = world.body(i);
        if (!b.isDynamic()) continue;
        const Eigen::Vector3d residual = b.mass * b.a - b.force - b.constraint_force;
        EXPECT_LT(residual.norm(), 1e-9 * (1.0 + b.constraint_force.norm() + b.force.norm()))
            << enumName(integrator) << " step " << s << " body " << i;
      }
    }
  }
}

TEST(PhysicsFeatherstone, RneaInvertsAbaAndCrbaAgrees) {
  for (int which : {0, 1, 2}) {
    World world = makeSystem(which, SolverKind::Featherstone);
    stirVelocities(world, 29u + which);
    world.evaluate();  // builds the tree, writes the bodies, fills the force accumulators
    ASSERT_TRUE(world.ok()) << world.status();
    ArticulatedSystem& sys = *world.reduced();
    const int n = sys.dofs();
    EXPECT_EQ(n, which == 0 ? 24 : which == 1 ? 30 : 3 + 1 + 12);
    std::mt19937 rng(3u);
    std::normal_distribution<double> g(0.0, 0.01);
    Eigen::VectorXd tau(n);
    for (int i = 0; i < n; ++i) tau(i) = g(rng);

    // RNEA(ABA(tau)) = tau.
    const Eigen::VectorXd udot = sys.forwardDynamics(world.bodies(), tau);
    const Eigen::VectorXd back = sys.inverseDynamics(world.bodies(), udot);
    EXPECT_LT((back - tau).norm(), 1e-10 * (1.0 + tau.norm())) << "system " << which;

    // CRBA: H symmetric positive definite, and H^-1 (tau - C) = ABA(tau) with C = RNEA(0).
    const Eigen::MatrixXd H = sys.massMatrix(world.bodies());
    EXPECT_LT((H - H.transpose()).norm(), 1e-14 * H.norm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
    const Eigen::VectorXd C = sys.inverseDynamics(world.bodies(), Eigen::VectorXd::Zero(n));
    const Eigen::VectorXd crba = H.llt().solve(tau - C);
    EXPECT_LT((crba - udot).norm(), 1e-9 * (1.0 + udot.norm())) << "system " << which;
    // And H is the kinetic energy's matrix: 1/2 u^T H u = sum of the bodies' kinetic energies
    // (when the base does not move: system 0's anchor shakes).
    if (which != 0) {
      EXPECT_NEAR(0.5 * sys.velocities().dot(H * sys.velocities()), world.kineticEnergy(),
                  1e-12 * (1.0 + world.kineticEnergy()));
    }
  }
}

// Contact responses (ArticulatedSystem::impulseResponse, by impulse propagation through the
// articulated inertias, O(n) a row) equal the dense H's (impulseResponseDense, Phi H^-1 Phi^T
// J^T by a Cholesky of the CRBA's H) on the chain, the floating base and the leg: rows on one
// body, on two bodies of the tree, and on a body and the world, at a stirred pose.
TEST(PhysicsFeatherstone, ContactResponsesByPropagationEqualTheDenseMassMatrix) {
  for (int which : {0, 1, 2}) {
    World world = makeSystem(which, SolverKind::Featherstone);
    stirVelocities(world, 41u + which);
    world.evaluate();
    ASSERT_TRUE(world.ok()) << world.status();
    const ArticulatedSystem& sys = *world.reduced();
    std::vector<int> dynamic;
    for (int i = 0; i < static_cast<int>(world.bodies().size()); ++i)
      if (world.bodies()[i].isDynamic()) dynamic.push_back(i);
    std::mt19937 rng(7u + which);
    std::normal_distribution<double> g(0.0, 1.0);
    const auto wrench = [&] {
      Vector6d w;
      for (int i = 0; i < 6; ++i) w(i) = g(rng);
      return w;
    };
    std::vector<ArticulatedSystem::ImpulseRow> rows;
    for (size_t k = 0; k < 3 * dynamic.size(); ++k) {
      ArticulatedSystem::ImpulseRow r;
      r.a = dynamic[k % dynamic.size()];
      r.ja = wrench();
      if (k % 3 == 1) {
        r.b = dynamic[(k * 7 + 3) % dynamic.size()];
        r.jb = wrench();
      }
      rows.push_back(r);
    }
    std::vector<std::vector<Vector6d>> fast, dense;
    ASSERT_TRUE(sys.impulseResponse(world.bodies(), rows, fast));
    ASSERT_TRUE(sys.impulseResponseDense(world.bodies(), rows, dense));
    double gap = 0.0, scale = 0.0;
    for (size_t k = 0; k < rows.size(); ++k)
      for (size_t i = 0; i < world.bodies().size(); ++i) {
        gap = std::max(gap, (fast[k][i] - dense[k][i]).norm());
        scale = std::max(scale, dense[k][i].norm());
      }
    EXPECT_GT(scale, 1e-3) << "system " << which;
    EXPECT_LT(gap, 1e-10 * scale) << "system " << which;
  }
}

// No drift by construction: over 5 s of the whipping chain (RK4, dt = 1/960 s, no projection at
// all) every joint holds to round-off (measured ~1e-16 m); the multiplier path without
// stabilization drifts by centimetres in the same run (docs/PHYSICS.md).
TEST(PhysicsFeatherstone, HoldsJointsExactlyForFiveSeconds) {
  for (Integrator integrator : {Integrator::RK4, Integrator::SymplecticEuler}) {
    PhysicsParams pp = exactPhysics(SolverKind::Featherstone);
    pp.integrator = integrator;
    pp.stabilization = Stabilization::None;  // ignored: nothing to stabilize
    ChainParams cp;
    cp.links = 8;
    if (integrator == Integrator::SymplecticEuler) cp.damping = 2e-4;  // first order: keep the whip tame
    ChainWorld cw = makeChainWorld(pp, cp, anchor(AnchorMotion::Fixed));
    double worst = 0.0;
    const int steps = static_cast<int>(5.0 / pp.dt);
    for (int i = 0; i < steps && cw.world.ok(); ++i) {
      cw.world.step();
      if (i % 16 == 0) worst = std::max(worst, cw.world.maxJointError());
    }
    ASSERT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_LT(worst, 1e-12) << enumName(integrator);
    EXPECT_NEAR(cw.world.time(), 5.0, 1e-9);
  }
}

// Energy with a fixed anchor (RK4, dt = 1e-4 s, 0.5 s through the first whip): the reduced step
// conserves it as well as the maximal one does (docs/PHYSICS.md: < 1e-9 J).
TEST(PhysicsFeatherstone, ConservesEnergyWithAFixedAnchor) {
  ChainParams cp;
  cp.links = 8;
  ChainWorld cw = makeChainWorld(exactPhysics(SolverKind::Featherstone, 1e-4), cp, anchor(AnchorMotion::Fixed));
  EXPECT_LT(testing::maxEnergyDrift(cw.world, 5000), 1e-9);
  ASSERT_TRUE(cw.world.ok()) << cw.world.status();
  EXPECT_LT(cw.chain.tip(cw.world).z(), -0.1);  // it fell
}

// A floating base: the hub with two chains, its total momentum changes only by gravity.
TEST(PhysicsFeatherstone, FloatingBaseConservesMomentum) {
  World world = makeSystem(1, SolverKind::Featherstone);
  PhysicsParams pp = world.params();
  stirVelocities(world, 41u);
  const auto momentum = [&] {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (const RigidBody& b : world.bodies()) p += b.mass * b.v;
    return p;
  };
  // Gravity pulls every body alike: total momentum changes by M g t exactly (joint forces and the
  // spring/damper pairs are internal).
  double mass = 0.0;
  for (const RigidBody& b : world.bodies()) mass += b.mass;
  const Eigen::Vector3d p0 = momentum();
  for (int i = 0; i < 96 && world.ok(); ++i) world.step();
  ASSERT_TRUE(world.ok()) << world.status();
  const Eigen::Vector3d expected = p0 + mass * pp.gravity * world.time();
  EXPECT_GT(p0.norm(), 0.1);
  // Momentum is not linear in joint coordinates, so RK4 keeps it only to its own error (measured
  // 3e-7 kg m/s over 0.1 s at dt = 1/960 s).
  EXPECT_LT((momentum() - expected).norm(), 1e-5 * (1.0 + expected.norm()));
  EXPECT_LT(world.maxJointError(), 1e-12);
}

// Closed loops (featherstone.h, "Closed loops"): the two loops of system 3 held closed by
// projection to the projection's tolerance, by Baumgarte to its drift; a repeated loop joint is
// refused plainly; adaptive dynamics refuses a loop.
TEST(PhysicsFeatherstone, ClosesLoops) {
  for (Stabilization s : {Stabilization::Projection, Stabilization::Baumgarte}) {
    PhysicsParams pp = exactPhysics(SolverKind::Featherstone);
    pp.stabilization = s;
    pp.dt = 1.0 / 240.0;
    World world = makeSystem(3, pp);
    double error = 0.0;
    for (int i = 0; i < 60 && world.ok(); ++i) {
      world.step();
      error = std::max(error, world.maxJointError());
    }
    ASSERT_TRUE(world.ok()) << world.status();
    EXPECT_EQ(world.reduced()->loopRows(), 6);
    EXPECT_LT(error, s == Stabilization::Projection ? 1e-12 : 1e-6) << enumName(s);
  }
  World twice = makeSystem(3, SolverKind::Featherstone);
  const auto& tie = static_cast<const SphericalJoint&>(*twice.joints().back());
  twice.addJoint(std::make_unique<SphericalJoint>(tie.bodyA(), tie.pointA(), tie.bodyB(), tie.pointB()));
  twice.step();
  EXPECT_NE(twice.status().find("redundant"), std::string::npos) << twice.status();
  PhysicsParams adaptive = exactPhysics(SolverKind::Featherstone);
  adaptive.adaptive_tolerance = 1e-6;
  World world(adaptive);
  ChainParams cp;
  cp.links = 3;
  const Chain a = addChain(world, cp, kWorldBody, Eigen::Vector3d(0, 0, 0));
  cp.direction = Eigen::Vector3d(1, 0, 0.2);
  joinTips(world, a, addChain(world, cp, kWorldBody, Eigen::Vector3d(0, 0, -0.05)));
  world.step();
  EXPECT_NE(world.status().find("cannot take a closed loop"), std::string::npos) << world.status();
}

// A joint type it does not know (a contact, or anything else) is named.
class Weld final : public Constraint {
 public:
  Weld(int a, int b) : Constraint(a, b) {}
  int dimension() const override { return 6; }
  const char* typeName() const override { return "weld"; }
  void evaluate(const RigidBody&, const RigidBody&, ConstraintRows& out) const override {
    out.C.setZero(6);
    out.ja.setIdentity(6, 6);
    out.jb = -out.ja;
    out.bias.setZero(6);
  }
};

TEST(PhysicsFeatherstone, SaysPlainlyWhenAJointTypeIsUnknown) {
  World world(exactPhysics(SolverKind::Featherstone));
  RigidBody b;
  b.name = "box";
  const int id = world.addDynamicBody(b);
  world.addJoint(std::make_unique<Weld>(kWorldBody, id));
  world.evaluate();
  ASSERT_FALSE(world.ok());
  EXPECT_NE(world.status().find("'weld'"), std::string::npos) << world.status();
  EXPECT_NE(world.status().find("featherstone"), std::string::npos) << world.status();
}

// The step-size knobs apply to reduced coordinates as to the multiplier solvers: at dt = 1/60 s
// (the whipping tip turns far more than a radian per frame) max_step_rotation (2 deg) takes many
// substeps and keeps the energy within 1 % over 2 s; tolerance chooses substeps by step doubling
// and keeps its estimate below the request.
TEST(PhysicsFeatherstone, AutomaticSubstepsAndToleranceChooseItsStep) {
  ChainParams cp;
  cp.links = 8;
  PhysicsParams pp = exactPhysics(SolverKind::Featherstone, 1.0 / 60.0);
  ASSERT_GT(pp.max_step_rotation, 0.0);
  ChainWorld cw = makeChainWorld(pp, cp, anchor(AnchorMotion::Fixed));
  const double e0 = cw.world.energy();
  int most = 0;
  double drift = 0.0;
  for (int i = 0; i < 120 && cw.world.ok(); ++i) {
    cw.world.step();
    most = std::max(most, cw.world.lastSubsteps());
    drift = std::max(drift, std::abs(cw.world.energy() - e0));
  }
  ASSERT_TRUE(cw.world.ok()) << cw.world.status();
  EXPECT_GT(most, 20);
  EXPECT_LT(drift, 0.01 * e0);
  EXPECT_LT(cw.world.maxJointError(), 1e-12);

  pp.max_step_rotation = 0.0;
  pp.tolerance = 1e-6;
  ChainWorld tol = makeChainWorld(pp, cp, anchor(AnchorMotion::Fixed));
  int substeps = 0;
  for (int i = 0; i < 30 && tol.world.ok(); ++i) {
    tol.world.step();
    substeps = std::max(substeps, tol.world.lastSubsteps());
    EXPECT_LE(tol.world.lastErrorEstimate(), 1e-6) << "step " << i;
  }
  ASSERT_TRUE(tol.world.ok()) << tol.world.status();
  EXPECT_GT(substeps, 2);
}

}  // namespace
}  // namespace ponyhop

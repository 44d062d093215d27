// Contacts and limits in the solve (physics/collisions.h) against analytic answers: a bounce to
// e^2 of the height, stick and slide on a slope at atan(mu), a capsule resting for 60 s, no energy
// gain at inelastic impacts (a free body and a chain), and joint limits that hold.
#include "physics/collisions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "physics/mesh_sdf.h"
#include "physics/models/chain.h"
#include "physics/world.h"

namespace ponyhop {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;

PhysicsParams params(double dt = 1.0 / 240.0, SolverKind solver = SolverKind::Dense) {
  PhysicsParams p;
  p.dt = dt;
  p.substeps = 1;
  p.solver = solver;
  // RATTLE, the default integrator; featherstone integrates in joint space with RK4.
  if (solver == SolverKind::Featherstone) p.integrator = Integrator::RK4;
  return p;
}

// A chain of `links` links of 5 cm (radius 1 cm) released horizontally along +x.
ChainParams horizontalChain(int links) {
  ChainParams chain;
  chain.links = links;
  chain.length = 0.05;
  chain.radius = 0.01;
  chain.direction = Vector3d(1, 0, 0);
  return chain;
}

RigidBody solidSphere(double m, double r, const Vector3d& x) {
  RigidBody b;
  b.name = "ball";
  b.mass = m;
  b.inertia = Vector3d::Constant(0.4 * m * r * r);
  b.x = x;
  return b;
}

RigidBody solidBox(double m, const Vector3d& h, const Vector3d& x, const Quaterniond& q) {
  RigidBody b;
  b.name = "box";
  b.mass = m;
  b.inertia =
      m / 3.0 * Vector3d(h.y() * h.y() + h.z() * h.z(), h.x() * h.x() + h.z() * h.z(), h.x() * h.x() + h.y() * h.y());
  b.x = x;
  b.q = q;
  return b;
}

// Drops a ball from height H (gap) with restitution e; returns the apex of the first bounce (gap).
double bounceApex(double e, double height, SolverKind solver) {
  World world(params(1.0 / 240.0, solver));
  const double r = 0.05;
  const int ball = world.addDynamicBody(solidSphere(1.0, r, Vector3d(0, 0, height + r)));
  CollisionParams cp;
  cp.restitution = e;
  cp.friction = 0.0;
  auto shared = std::make_shared<Collisions>(cp, solver);
  Collisions& col = *shared;
  const int s = col.addShape(ball, Shape::sphere(r));
  const int g = col.addShape(kWorldBody, Shape::plane(Vector3d::UnitZ()));
  col.addPair(s, g);
  col.attach(world);
  bool bounced = false;
  double apex = 0.0;
  for (int i = 0; i < 240 * 4 && world.ok(); ++i) {
    world.step();
    const RigidBody& b = world.body(ball);
    if (!bounced && b.v.z() > 0.0) bounced = true;
    if (bounced) {
      apex = std::max(apex, b.x.z() - r);
      if (b.v.z() < 0.0) break;  // past the apex
    }
  }
  EXPECT_TRUE(world.ok()) << world.status();
  EXPECT_TRUE(bounced);
  return apex;
}

TEST(Contact, BallBouncesToRestitutionSquaredOfItsHeight) {
  for (SolverKind solver : {SolverKind::Dense, SolverKind::Tree, SolverKind::Featherstone}) {
    for (double e : {0.3, 0.5, 0.8}) {
      const double apex = bounceApex(e, 1.0, solver);
      // The apex between two steps: sampled at dt, at most g dt^2 / 8 below the true one.
      EXPECT_NEAR(apex / (e * e), 1.0, 0.01) << "e = " << e;
      std::printf("bounce e = %.1f (%s): apex / (e^2 H) = %.6f\n", e, std::string(enumName(solver)).c_str(),
                  apex / (e * e));
      RecordProperty("apex_over_e2_" + std::to_string(static_cast<int>(100 * e)), std::to_string(apex / (e * e)));
    }
  }
}

// A box on a plane tilted by `angle` about y, friction mu: the velocity along the slope after
// `seconds`, started at rest.
double slopeSpeed(double angle, double mu, double seconds, double* normal_drift = nullptr) {
  World world(params());
  const Vector3d h(0.1, 0.08, 0.05);
  const Quaterniond tilt(Eigen::AngleAxisd(angle, Vector3d::UnitY()));
  const Vector3d up = tilt * Vector3d::UnitZ();
  const int box = world.addDynamicBody(solidBox(2.0, h, up * h.z(), tilt));
  CollisionParams cp;
  cp.friction = mu;
  auto shared = std::make_shared<Collisions>(cp);
  Collisions& col = *shared;
  const int s = col.addShape(box, Shape::box(h));
  const int g = col.addShape(kWorldBody, Shape::plane(up));
  col.addPair(s, g);
  col.attach(world);
  const int steps = static_cast<int>(std::lround(seconds * 240.0));
  for (int i = 0; i < steps && world.ok(); ++i) world.step();
  EXPECT_TRUE(world.ok()) << world.status();
  const Vector3d down_slope = tilt * Vector3d::UnitX();  // -x tilted: downhill is +x rotated... sign below
  if (normal_drift) *normal_drift = std::abs(world.body(box).x.dot(up) - h.z());
  return std::abs(world.body(box).v.dot(down_slope));
}

TEST(Contact, BoxOnASlopeSticksBelowTheFrictionAngleAndSlidesAboveIt) {
  const double mu = 0.4, g = 9.81;
  const double critical = std::atan(mu);
  double drift = 0.0;
  // Below: at rest (a tiny numerical creep at most).
  EXPECT_LT(slopeSpeed(critical - 0.05, mu, 2.0, &drift), 1e-9);
  EXPECT_LT(drift, 1e-9);
  // Above: a = g (sin a - mu cos a), measured between t = 1 s and 2 s.
  for (double a : {critical + 0.05, critical + 0.2}) {
    const double v1 = slopeSpeed(a, mu, 1.0), v2 = slopeSpeed(a, mu, 2.0);
    const double expected = g * (std::sin(a) - mu * std::cos(a));
    EXPECT_NEAR((v2 - v1) / expected, 1.0, 0.01) << "angle " << a;
    std::printf("slope %.4f rad, mu %.2f: measured / g (sin a - mu cos a) = %.6f\n", a, mu, (v2 - v1) / expected);
  }
}

// A box sliding on the ground along `heading` (rad from the x axis), turned with it so that only
// the contact's tangent frame differs between headings: that frame is fixed by the normal
// (normal.unitOrthogonal(): +y and -x for the ground), so heading 0 slides along one of its
// axes and heading pi/4 along its diagonal. Returns the velocity after 0.2 s.
Vector3d slideVelocity(double heading) {
  World world(params());
  const Vector3d h(0.05, 0.05, 0.02);
  const Quaterniond turn(Eigen::AngleAxisd(heading, Vector3d::UnitZ()));
  const int box = world.addDynamicBody(solidBox(1.0, h, Vector3d(0, 0, h.z()), turn));
  world.body(box).v = turn * Vector3d(2.0, 0, 0);
  CollisionParams cp;
  cp.friction = 0.5;
  auto shared = std::make_shared<Collisions>(cp);
  shared->addPair(shared->addShape(box, Shape::box(h)), shared->addShape(kWorldBody, Shape::plane(Vector3d::UnitZ())));
  shared->attach(world);
  for (int i = 0; i < 48 && world.ok(); ++i) world.step();
  EXPECT_TRUE(world.ok()) << world.status();
  return world.body(box).v;
}

TEST(Contact, FrictionIsAConeSlidingAlongADiagonalSlowsAsAlongAnAxis) {
  // A cone: the friction is mu N opposite the slip whatever its direction, so both boxes slow by
  // mu g t = 0.5 * 9.81 * 0.2 = 0.981 m/s and keep their headings. A box (a clamp of each
  // tangent to mu N) would slow the diagonal one sqrt(2) times faster.
  const Vector3d axis = slideVelocity(0.0), diagonal = slideVelocity(M_PI / 4.0);
  const double expected = 2.0 - 0.5 * 9.81 * 0.2;
  std::printf("sliding box after 0.2 s: along an axis %.9f m/s, along the diagonal %.9f m/s (mu g t: %.9f)\n",
              axis.head<2>().norm(), diagonal.head<2>().norm(), expected);
  EXPECT_NEAR(axis.head<2>().norm(), expected, 1e-3);
  EXPECT_NEAR(diagonal.head<2>().norm(), axis.head<2>().norm(), 1e-9);
  EXPECT_NEAR(std::atan2(diagonal.y(), diagonal.x()), M_PI / 4.0, 1e-9);
  EXPECT_NEAR(std::atan2(axis.y(), axis.x()), 0.0, 1e-9);
}

TEST(Contact, CapsuleRestingOnTheGroundDoesNotDriftInSixtySeconds) {
  World world(params());
  const double r = 0.03, half = 0.1;
  RigidBody b;
  b.name = "capsule";
  b.mass = 0.5;
  b.inertia = Vector3d(0.002, 0.002, 0.0002);
  const Quaterniond lying = rotationBetween(Vector3d::UnitZ(), Vector3d::UnitX());
  b.q = lying;
  b.x = Vector3d(0.2, -0.1, r);
  const int cap = world.addDynamicBody(b);
  auto shared = std::make_shared<Collisions>(CollisionParams{});
  Collisions& col = *shared;
  col.addPair(col.addShape(cap, Shape::capsule(half, r, r)), col.addShape(kWorldBody, Shape::plane(Vector3d::UnitZ())));
  col.attach(world);
  for (int i = 0; i < 240 * 60 && world.ok(); ++i) world.step();
  ASSERT_TRUE(world.ok()) << world.status();
  const RigidBody& c = world.body(cap);
  EXPECT_LT((c.x - Vector3d(0.2, -0.1, r)).norm(), 1e-9);
  EXPECT_LT(c.q.angularDistance(lying), 1e-9);
  EXPECT_LT(c.v.norm(), 1e-9);
  std::printf("resting capsule after 60 s: drift %.3g m, turn %.3g rad, speed %.3g m/s\n",
              (c.x - Vector3d(0.2, -0.1, r)).norm(), c.q.angularDistance(lying), c.v.norm());
}

TEST(Contact, InelasticImpactsNeverRaiseTheEnergy) {
  // A tumbling box thrown onto the ground: every contact stage lowers the kinetic energy, and the
  // total (kinetic + potential) never rises from one step to the next.
  World world(params());
  const Vector3d h(0.1, 0.05, 0.03);
  const int box = world.addDynamicBody(
      solidBox(1.0, h, Vector3d(0, 0, 0.5), Quaterniond(Eigen::AngleAxisd(0.6, Vector3d(1, 1, 0).normalized()))));
  world.body(box).v = Vector3d(1.0, 0.5, -1.0);
  world.body(box).w = Vector3d(3.0, -2.0, 5.0);
  CollisionParams cp;
  cp.friction = 0.6;
  auto shared = std::make_shared<Collisions>(cp);
  Collisions& col = *shared;
  col.addPair(col.addShape(box, Shape::box(h)), col.addShape(kWorldBody, Shape::plane(Vector3d::UnitZ())));
  col.attach(world);
  double e_prev = world.energy(), worst_rise = -1e300;
  for (int i = 0; i < 240 * 3 && world.ok(); ++i) {
    world.step();
    worst_rise = std::max(worst_rise, world.energy() - e_prev);
    e_prev = world.energy();
  }
  ASSERT_TRUE(world.ok()) << world.status();
  EXPECT_GT(col.stats().impacts, 0);
  EXPECT_LE(col.stats().max_energy_gain, 1e-12);
  // RATTLE's own bounded energy error in free flight is ~1e-15 here; the push-out of an overlap
  // of at most impact_tolerance lifts the box by that much at most.
  EXPECT_LE(worst_rise, 1.0 * 9.81 * 1e-4);
  std::printf("tumbling box: impulse energy gain max %.3g J, step-to-step energy rise max %.3g J\n",
              col.stats().max_energy_gain, worst_rise);
  EXPECT_LT(world.body(box).v.norm(), 1e-6);  // at rest on the ground in the end
}

// No pass-through (docs/PHYSICS.md, "No pass-through"): a ball of radius 5 mm shot at 10 m/s onto
// a 1 cm plate given as a distance grid moves 42 mm in a step, through the plate and clear of it,
// so no contact is found at either end of that step. Only the check of how far a shape moved
// against the grid since the last stage (Collisions::movedTooFar) catches it: the World splits
// the step, and the ball stops on the plate instead of falling on below it. In tolerance mode as
// well: free flight under gravity has no integration error, so only the impact check splits there.
// A 20 x 20 cm plate 1 cm thick (top at z = 5 mm) as a distance grid of 2 mm cells.
std::shared_ptr<SignedDistanceGrid> thinPlate() {
  const std::vector<Vector3d> v = {{-0.1, -0.1, -0.005}, {0.1, -0.1, -0.005}, {0.1, 0.1, -0.005}, {-0.1, 0.1, -0.005},
                                   {-0.1, -0.1, 0.005},  {0.1, -0.1, 0.005},  {0.1, 0.1, 0.005},  {-0.1, 0.1, 0.005}};
  const std::vector<uint32_t> idx = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                     1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  auto plate = std::make_shared<SignedDistanceGrid>();
  EXPECT_TRUE(plate->build(v, idx, 0.002, 0.02).ok());
  return plate;
}

void fastBallOntoAThinGrid(double tolerance) {
  const std::shared_ptr<SignedDistanceGrid> plate = thinPlate();
  PhysicsParams pp = params();
  pp.tolerance = tolerance;
  World world(pp);
  const double r = 0.005;
  const int ball = world.addDynamicBody(solidSphere(0.01, r, Vector3d(0.0, 0.0, 0.03)));
  world.body(ball).v = Vector3d(0.0, 0.0, -10.0);
  CollisionParams cp;
  cp.friction = 0.0;
  auto shared = std::make_shared<Collisions>(cp);
  Collisions& col = *shared;
  col.addPair(col.addShape(ball, Shape::sphere(r)), col.addShape(kWorldBody, Shape::grid(plate)));
  col.attach(world);
  double lowest = 1e300;
  for (int i = 0; i < 60 && world.ok(); ++i) {
    world.step();
    lowest = std::min(lowest, world.body(ball).x.z());
  }
  ASSERT_TRUE(world.ok()) << world.status();
  std::printf(
      "ball at 10 m/s onto a 1 cm plate (tolerance %g m): lowest centre %.3f mm (plate top 5 mm, radius 5 mm), "
      "%d impacts\n",
      tolerance, 1e3 * lowest, col.stats().impacts);
  EXPECT_GT(lowest, 0.005 + r - 1e-3) << "the ball went into or through the plate";
  EXPECT_GT(col.stats().impacts, 0);
  EXPECT_EQ(col.stats().too_fast, 0);
}

TEST(Contact, AFastBallDoesNotPassThroughAThinGrid) { fastBallOntoAThinGrid(0.0); }
TEST(Contact, AFastBallDoesNotPassThroughAThinGridInToleranceMode) { fastBallOntoAThinGrid(1e-3); }

// Skipping a search (docs/PHYSICS.md, "No pass-through", 4): a link whose last search bounded its
// gap beyond reach is not searched again while it has moved too little to close that gap, and is
// searched, and its contact found, as soon as it has moved far enough.
TEST(Contact, AGridSearchIsSkippedOnlyWhileTheLinkCannotHaveClosedItsGap) {
  const std::shared_ptr<SignedDistanceGrid> plate = thinPlate();
  World world(params());
  const double r = 0.004, top = 0.005;
  RigidBody body = solidSphere(0.01, r, Vector3d(0.0, 0.0, top + r + 0.006));
  body.q = Quaterniond(Eigen::AngleAxisd(0.5 * std::numbers::pi, Vector3d::UnitY()));  // the capsule lies flat
  const int link = world.addDynamicBody(body);
  auto col = std::make_shared<Collisions>(CollisionParams{});
  col->addPair(col->addShape(link, Shape::capsule(0.02, r, r)), col->addShape(kWorldBody, Shape::grid(plate)));
  std::vector<RigidBody> bodies = world.bodies();
  long queries = 0;
  EXPECT_TRUE(col->detect(bodies, 0.0, &queries).empty());  // 6 mm above the plate
  EXPECT_GT(queries, 0);
  // 0.1 mm lower and 0.1 mm aside: the bound from the last search still holds, no query.
  bodies[link].x += Vector3d(1e-4, 0.0, -1e-4);
  queries = 0;
  EXPECT_TRUE(col->detect(bodies, 0.0, &queries).empty());
  EXPECT_EQ(queries, 0) << "a link that cannot have closed its gap was searched again";
  // 7 mm lower: 1 mm into the plate. The bound no longer holds; the search runs and finds it.
  bodies[link].x.z() = top + r - 0.001;
  queries = 0;
  const std::vector<Collisions::Row> rows = col->detect(bodies, 0.0, &queries);
  EXPECT_GT(queries, 0);
  ASSERT_FALSE(rows.empty()) << "a link that moved into the plate was skipped";
  EXPECT_NEAR(rows[0].gap, -0.001, 2e-4);
  // What a skip leaves out is what a search would not find: a fresh collider agrees.
  auto fresh = std::make_shared<Collisions>(CollisionParams{});
  fresh->addPair(fresh->addShape(link, Shape::capsule(0.02, r, r)), fresh->addShape(kWorldBody, Shape::grid(plate)));
  const std::vector<Collisions::Row> again = fresh->detect(bodies, 0.0);
  ASSERT_EQ(again.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(again[i].gap, rows[i].gap);
}

// Featherstone twice: every joint moving, and adaptive dynamics with half the joints rigid at every
// step (a rigid stretch still collides link by link).
TEST(Contact, ChainFallingOnTheGroundKeepsItsJointsAndLosesEnergy) {
  for (int variant = 0; variant < 4; ++variant) {
    const SolverKind solver = variant == 0   ? SolverKind::Dense
                              : variant == 1 ? SolverKind::Tree
                                             : SolverKind::Featherstone;
    SCOPED_TRACE(variant);
    PhysicsParams pp = params(1.0 / 240.0, solver);
    pp.substeps = 2;
    if (variant == 3) pp.adaptive_joints = 3;  // of 6: the other three rigid at every step
    const ChainParams chain = horizontalChain(6);
    ChainWorld cw = makeChainWorld(pp, chain, AnchorParams{});
    ASSERT_TRUE(cw.world.ok()) << cw.world.status();
    // The chain hangs from the origin; the ground is 0.2 m below: the horizontal chain swings
    // down and its links hit the floor.
    CollisionParams cp;
    cp.friction = 0.3;
    auto shared = std::make_shared<Collisions>(cp, solver);
    Collisions& col = *shared;
    const int ground = col.addShape(kWorldBody, Shape::plane(Vector3d::UnitZ(), Vector3d(0, 0, -0.2)));
    for (int i = 0; i < chain.links; ++i) {
      const double ra = cw.chain.radii[i], rb = i + 1 < chain.links ? cw.chain.radii[i + 1] : ra;
      col.addPair(col.addShape(cw.chain.links[i], Shape::capsule(0.5 * chain.length, ra, rb)), ground);
    }
    col.attach(cw.world);
    double e_prev = cw.world.energy(), worst_rise = -1e300, lowest = 1e9;
    for (int i = 0; i < 240 * 3 && cw.world.ok(); ++i) {
      cw.world.step();
      worst_rise = std::max(worst_rise, cw.world.energy() - e_prev);
      e_prev = cw.world.energy();
      for (const CapsuleSegment& s : cw.chain.segments(cw.world))
        lowest = std::min({lowest, s.top.z() - s.radius_top, s.bottom.z() - s.radius_bottom});
    }
    ASSERT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_GT(col.stats().impacts, 0);
    EXPECT_GT(lowest, -0.2 - 1e-4);  // never deeper than the impact tolerance
    EXPECT_LT(cw.world.maxJointError(), 1e-9);
    EXPECT_LE(col.stats().max_energy_gain, 1e-12);
    EXPECT_LE(worst_rise, 1e-4);
    std::printf("falling chain (%s%s): lowest %.3g m below the ground, joint error %.3g m, energy rise max %.3g J\n",
                std::string(enumName(solver)).c_str(), variant == 3 ? ", adaptive" : "", -0.2 - lowest,
                cw.world.maxJointError(), worst_rise);
  }
}

// The contact stage solves with the World's factorization of the joints instead of its own only
// while it is the one made at the present state (World::solverFactoredAt): after a stabilized
// step, not after any body moved by a bit, nor after the solver factored something else.
TEST(Contact, TheStageReusesTheWorldsFactorizationOnlyAtItsState) {
  PhysicsParams pp = params(1.0 / 240.0, SolverKind::Tree);
  pp.integrator = Integrator::RK4;
  pp.stabilization = Stabilization::Projection;
  ChainWorld cw = makeChainWorld(pp, horizontalChain(4), AnchorParams{});
  ASSERT_TRUE(cw.world.ok()) << cw.world.status();
  EXPECT_EQ(cw.world.solverFactoredAt(cw.world.bodies()), nullptr);  // nothing factored yet
  cw.world.step();
  ASSERT_TRUE(cw.world.ok()) << cw.world.status();
  EXPECT_EQ(cw.world.solverFactoredAt(cw.world.bodies()), &cw.world.solver());
  std::vector<RigidBody> moved = cw.world.bodies();
  moved[cw.chain.links[2]].x.x() = std::nextafter(moved[cw.chain.links[2]].x.x(), 1.0);
  EXPECT_EQ(cw.world.solverFactoredAt(moved), nullptr);
  moved = cw.world.bodies();
  moved[cw.chain.links[1]].q.coeffs().w() = std::nextafter(moved[cw.chain.links[1]].q.w(), 2.0);
  EXPECT_EQ(cw.world.solverFactoredAt(moved), nullptr);
  cw.world.energy();  // a readout: factors nothing
  EXPECT_EQ(cw.world.solverFactoredAt(cw.world.bodies()), &cw.world.solver());
}

TEST(Contact, SwingConeAndTwistLimitHold) {
  // A two-link chain hanging from a fixed anchor, thrown sideways: the first link may swing 20
  // degrees from the vertical, the second 15 from the first; twist within 10 degrees.
  PhysicsParams pp = params();
  ChainParams chain;
  chain.links = 2;
  chain.length = 0.1;
  chain.direction = Vector3d(0, 0, -1);
  ChainWorld cw = makeChainWorld(pp, chain, AnchorParams{});
  ASSERT_TRUE(cw.world.ok());
  auto shared = std::make_shared<Collisions>(CollisionParams{});
  Collisions& col = *shared;
  const double cone0 = 20.0 * std::numbers::pi / 180.0, cone1 = 15.0 * std::numbers::pi / 180.0;
  const double twist = 10.0 * std::numbers::pi / 180.0;
  const int l0 = cw.chain.links[0], l1 = cw.chain.links[1];
  col.addConeLimit(kWorldBody, Vector3d::UnitZ(), l0, Vector3d::UnitZ(), cone0);
  col.addConeLimit(l0, Vector3d::UnitZ(), l1, Vector3d::UnitZ(), cone1);
  col.addTwistLimit(l0, l1, Vector3d::UnitZ(), twist, cw.world.bodies());
  col.attach(cw.world);
  for (int id : {l0, l1}) {
    cw.world.body(id).v = Vector3d(2.0, 1.0, 0.0);
    cw.world.body(id).w = Vector3d(0.0, 0.0, 20.0);
  }
  cw.world.projectVelocities();
  double worst0 = 0, worst1 = 0, worst_twist = 0;
  for (int i = 0; i < 240 * 2 && cw.world.ok(); ++i) {
    cw.world.step();
    const Vector3d z0 = cw.world.body(l0).q * Vector3d::UnitZ(), z1 = cw.world.body(l1).q * Vector3d::UnitZ();
    worst0 = std::max(worst0, std::acos(std::clamp(z0.z(), -1.0, 1.0)));
    worst1 = std::max(worst1, std::acos(std::clamp(z0.dot(z1), -1.0, 1.0)));
    const Quaterniond rel = cw.world.body(l0).q.conjugate() * cw.world.body(l1).q;
    worst_twist = std::max(worst_twist, std::abs(2.0 * std::atan2(rel.vec().z(), rel.w())));
  }
  ASSERT_TRUE(cw.world.ok()) << cw.world.status();
  EXPECT_LT(worst0, cone0 + 1e-6);
  EXPECT_LT(worst1, cone1 + 1e-6);
  EXPECT_LT(worst_twist, twist + 1e-6);
  EXPECT_GT(worst0, cone0 - 0.01);  // the throw does reach the limit
}

}  // namespace
}  // namespace ponyhop

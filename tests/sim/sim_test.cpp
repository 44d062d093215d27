// The sim layer: a scene made into a World with any number of controllers and contact sets, the
// one step order, snapshots that restore bit for bit, state carried across a rebuild, a World
// that may move, and a library that links no GL and no importer.
#include "sim/sim.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "common/sanitizers.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

// Every body's state, bit for bit.
std::string stateBits(const World& w) {
  std::string out;
  for (const RigidBody& b : w.bodies()) {
    const BodyState& s = b.state();
    out.append(reinterpret_cast<const char*>(s.x.data()), sizeof(double) * 3);
    out.append(reinterpret_cast<const char*>(s.q.coeffs().data()), sizeof(double) * 4);
    out.append(reinterpret_cast<const char*>(s.v.data()), sizeof(double) * 3);
    out.append(reinterpret_cast<const char*>(s.w.data()), sizeof(double) * 3);
  }
  return out;
}

TEST(Sim, TwoHoppersInOneWorldBothHopForTenSeconds) {
  Sim sim(loadScene("assets/scenes/two_hoppers.json"));
  ASSERT_EQ(sim.hoppers().size(), 2u);
  const Hopper& a = *sim.hopper(0);
  const Hopper& b = *sim.hopper(1);
  ASSERT_NE(a.model().body, b.model().body);
  double a_max_tilt = 0.0, b_max_tilt = 0.0, a_min_z = 1e9, b_min_z = 1e9;
  ASSERT_TRUE(sim.advanceTo(10.0)) << sim.status();
  // Sampled as it goes: both bodies stay up, both legs bounce.
  Sim again(loadScene("assets/scenes/two_hoppers.json"));
  while (again.ok() && again.time() < 10.0 - 1e-9) {
    again.step();
    const World& w = again.world();
    a_max_tilt = std::max(a_max_tilt, again.hopper(0)->tilt(w));
    b_max_tilt = std::max(b_max_tilt, again.hopper(1)->tilt(w));
    a_min_z = std::min(a_min_z, w.body(again.hopper(0)->model().body).x.z());
    b_min_z = std::min(b_min_z, w.body(again.hopper(1)->model().body).x.z());
  }
  ASSERT_TRUE(again.ok()) << again.status();
  const World& w = sim.world();
  const Eigen::Vector3d pa = w.body(a.model().body).x, pb = w.body(b.model().body).x;
  std::printf(
      "[ two hoppers ] 10 s: A %d hops, at (%.2f, %.2f), max tilt %.1f deg, lowest %.2f m; "
      "B %d hops, at (%.2f, %.2f), max tilt %.1f deg, lowest %.2f m, apex %.3f m\n",
      a.hops(), pa.x(), pa.y(), a_max_tilt * 57.3, a_min_z, b.hops(), pb.x(), pb.y(), b_max_tilt * 57.3, b_min_z,
      b.lastApex());
  EXPECT_GT(a.hops(), 12);
  EXPECT_GT(b.hops(), 10);
  EXPECT_NEAR(b.attitude(w)[2] * 57.2958, 90.0, 5.0) << "B turns to its own heading";
  EXPECT_LT(a_max_tilt * 57.3, 15.0);
  EXPECT_LT(b_max_tilt * 57.3, 15.0);
  EXPECT_GT(a_min_z, 0.6);
  EXPECT_GT(b_min_z, 0.6);
  EXPECT_GT(pa.x(), 2.0) << "A runs forward at 0.5 m/s";
  EXPECT_LT(std::abs(pb.x()), 0.5) << "B hops in place";
  EXPECT_NEAR(b.lastApex(), 1.2, 0.05) << "B keeps its own height command";
}

TEST(Sim, OneHopperStepsAsItDidAloneWhenASecondJoins) {
  // The first hopper's motion does not depend on a second, independent one in the same world
  // (controllers and contact sets are per hopper; the solve is block-separable). The step is
  // fixed: automatic substeps follow the fastest body of the whole world, which couples them.
  Scene pair_scene = loadScene("assets/scenes/two_hoppers.json");
  pair_scene.physics.max_step_rotation = 0.0;
  Scene one = pair_scene;
  one.hoppers.clear();
  Sim alone(one);
  Sim pair(pair_scene);
  ASSERT_TRUE(alone.advanceTo(2.0)) << alone.status();
  ASSERT_TRUE(pair.advanceTo(2.0)) << pair.status();
  const Eigen::Vector3d xa = alone.world().body(alone.hopper()->model().body).x;
  const Eigen::Vector3d xp = pair.world().body(pair.hopper()->model().body).x;
  EXPECT_LT((xa - xp).norm(), 1e-9) << "alone " << xa.transpose() << ", with a second hopper " << xp.transpose();
  EXPECT_EQ(alone.hopper()->hops(), pair.hopper()->hops());
}

TEST(Sim, SnapshotRestoresBitForBitWithTheControllersState) {
  Sim sim(loadScene("assets/scenes/ponytail_hopper.json"));
  ASSERT_TRUE(sim.advanceTo(0.7)) << sim.status();
  const SimSnapshot snap = sim.snapshot();
  ASSERT_TRUE(sim.advanceTo(1.4)) << sim.status();
  const std::string first = stateBits(sim.world());
  const int hops = sim.hopper()->hops();
  const HopperPhase phase = sim.hopper()->phase();
  sim.restore(snap);
  EXPECT_DOUBLE_EQ(sim.time(), snap.world.step.time);
  ASSERT_TRUE(sim.advanceTo(1.4)) << sim.status();
  EXPECT_EQ(stateBits(sim.world()), first) << "the replay from the snapshot differs";
  EXPECT_EQ(sim.hopper()->hops(), hops);
  EXPECT_EQ(sim.hopper()->phase(), phase);
  // A snapshot of a running world revives it after it stopped.
  sim.world().body(sim.hopper()->model().body).x.x() = std::nan("");
  EXPECT_FALSE(sim.step());
  sim.restore(snap);
  EXPECT_TRUE(sim.ok()) << sim.status();
  ASSERT_TRUE(sim.advanceTo(1.4)) << sim.status();
  EXPECT_EQ(stateBits(sim.world()), first);
}

TEST(Sim, CarryStateKeepsPosesAndShiftsPrescribedMotion) {
  const Scene scene = loadScene("assets/scenes/chain.json");
  Sim from(scene);
  ASSERT_TRUE(from.advanceTo(0.5)) << from.status();
  Scene edited = scene;
  edited.physics.gravity.z() *= 0.5;  // an edit that keeps the bodies
  Sim to(edited);
  ASSERT_TRUE(to.carryStateFrom(from, from.time()));
  for (int i = 0; i < to.world().bodyCount(); ++i) {
    const RigidBody& a = from.world().body(i);
    const RigidBody& b = to.world().body(i);
    EXPECT_EQ((a.x - b.x).norm(), 0.0) << "body " << i;
    EXPECT_EQ((a.v - b.v).norm(), 0.0) << "body " << i;
  }
  EXPECT_EQ(to.time(), 0.0);
  // An edit that moves the attachment no longer closes the joints: refused.
  Scene moved = scene;
  moved.anchor->position.x() += 0.1;
  Sim far(moved);
  EXPECT_FALSE(far.carryStateFrom(from, from.time()));
}

TEST(Sim, AWorldMayMoveWithItsControllers) {
  Scene scene = loadScene("assets/scenes/two_hoppers.json");
  Sim reference(scene);
  ASSERT_TRUE(reference.advanceTo(1.0));
  // The same world built, stepped half-way, moved into a new object and stepped on.
  Sim sim(scene);
  ASSERT_TRUE(sim.advanceTo(0.5));
  World moved = std::move(sim.world());
  while (moved.ok() && moved.time() + 0.5 * scene.physics.dt <= 1.0) moved.step();
  ASSERT_TRUE(moved.ok()) << moved.status();
  EXPECT_EQ(stateBits(moved), stateBits(reference.world()));
}

TEST(Sim, WatchedPointsAreDefinedOnce) {
  Sim sim(loadScene("assets/scenes/ponytail_hopper.json"));
  const World& w = sim.world();
  const int body = sim.hopper()->model().body;
  EXPECT_EQ(sim.followPoint("hopper"), w.body(body).x);
  EXPECT_EQ(sim.followPoint(""), w.body(body).x) << "no head: the hopper";
  EXPECT_EQ(sim.followPoint("chain"), w.body(sim.chain()->links.front()).x);
  EXPECT_EQ(sim.trackedPoint(), sim.chain()->tip(w)) << "the chain's free end first";
}

TEST(Sim, AHeadNeedsAnAssetLoader) {
  try {
    Sim sim(loadScene("assets/scenes/ponytail.json"));
    ADD_FAILURE() << "a head scene built without a mesh loader";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("head.mesh"), std::string::npos) << e.what();
  }
}

// What this test binary links: the sim layer pulls in no GL, no OSMesa and no importer.
TEST(Sim, LinksNoGlNoImporter) {
  std::ifstream maps("/proc/self/maps");
  std::stringstream ss;
  ss << maps.rdbuf();
  const std::string m = ss.str();
  ASSERT_NE(m.find("libstdc++"), std::string::npos) << "cannot read the process's mapped libraries";
  for (const char* lib : {"libOSMesa", "libGL", "libassimp", "libglfw", "libEGL"}) {
    EXPECT_EQ(m.find(lib), std::string::npos) << lib << " is mapped into a sim-only test";
  }
}

// RATTLE with the default step control keeps the whipping chain's energy over a long run: the
// substep count of each dt holds at both its ends (World::step) and no substep is split for its
// turn, so the variable steps stay time-symmetric. With the count from the start alone the energy
// fell about 0.05 % of E0 per simulated second (2.2-3.8 % after 60 s); with the split decided at
// a substep's end 0.33 % after 60 s here; now 0.10 % (bound 0.25 %). Under the sanitizers the
// first 15 s (about ten whips; 47 s of the ASan run's time for the minute): the drift of 0.05 %
// per second still fails it there.
TEST(Sim, TheDefaultMethodKeepsTheEnergyOfAWhippingChainForAMinute) {
  Sim sim(loadScene("assets/scenes/chain.json",
                    {{"physics.integrator", "rattle"}, {"physics.dt", "0.004166666666666667"}}));
  const int seconds = testing::fullOrSanitized(60, 15);
  const double e0 = sim.chainEnergy();
  double worst = 0.0;
  for (int i = 0; i < seconds * 240 && sim.ok(); ++i) {
    sim.step();
    worst = std::max(worst, std::abs(sim.chainEnergy() - e0));
  }
  ASSERT_TRUE(sim.ok()) << sim.status();
  std::printf("max |E - E0| / E0 over %d s: %.3f %%\n", seconds, 100.0 * worst / std::abs(e0));
  EXPECT_LT(worst, 0.0025 * std::abs(e0));
}

// The default method's energy on the released 8-link chain (docs/STABILITY.md, "Why 1.25x" and
// "Long runs drift"): max |E - E0| / |E0| over every step (E against the hanging chain, as the
// bench's energy_drift_rel), at each dt over five starting directions; then 60 s at 1/240. Not
// run by ctest: build/tests/sim_tests --gtest_also_run_disabled_tests --gtest_filter='*EnergyTable*'
TEST(Sim, DISABLED_DefaultMethodEnergyTable) {
  const char* directions[] = {"[1,0,0]", "[1,0,0.02]", "[1,0.05,0]", "[1,0,-0.03]", "[1,0.02,0.02]"};
  const auto drift = [&](int rate, const char* direction, double seconds) {
    char dt[32];
    std::snprintf(dt, sizeof dt, "%.17g", 1.0 / rate);
    Sim sim(loadScene("assets/scenes/chain.json",
                      {{"physics.integrator", "rattle"}, {"physics.dt", dt}, {"chain.direction", direction}}));
    const double e0 = sim.chainEnergy();
    double worst = 0.0;
    for (long i = 0; i < std::lround(seconds * rate) && sim.ok(); ++i) {
      sim.step();
      worst = std::max(worst, std::abs(sim.chainEnergy() - e0));
    }
    EXPECT_TRUE(sim.ok()) << sim.status();
    return 100.0 * worst / std::abs(e0);
  };
  std::printf("| dt | max abs(E - E0)/E0 over 10 s, five directions (%%) |\n|---|---|\n");
  for (int rate : {60, 120, 240, 480, 960, 1920}) {
    std::printf("| 1/%d |", rate);
    for (const char* d : directions) std::printf(" %.2f", drift(rate, d, 10.0));
    std::printf(" |\n");
  }
  std::printf("60 s at 1/240:");
  for (int i = 0; i < 3; ++i) std::printf(" %.2f %%", drift(240, directions[i], 60.0));
  std::printf("\n");
}

}  // namespace
}  // namespace ponyhop

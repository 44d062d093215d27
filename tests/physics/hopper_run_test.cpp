// The hopper runs, headless, and is measured: 1 m/s along x, then along y, then diagonally, then
// a stop (mean speed over the last 10 s of each leg within 10 % of the command); the heading
// follows its command; and the range of speeds that track within 10 % is measured and printed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <vector>

#include "common/physics_util.h"
#include "common/sanitizers.h"
#include "physics/models/hopper.h"

namespace ponyhop {
namespace {

using testing::kRad;

struct Runner : testing::HopperWorld {
  double max_tilt = 0.0;

  explicit Runner(const HopperParams& hp) : HopperWorld(hp) {}
  Eigen::Vector3d position() const { return body().x; }
  void until(double T) {
    while (world.ok() && world.time() < T - 1e-9) {
      world.step();
      max_tilt = std::max(max_tilt, hopper->tilt(world));
    }
  }
  // Mean horizontal velocity over [t0, t1] (displacement / time: exact over whole hops or not).
  Eigen::Vector2d meanVelocity(double t0, double t1) {
    until(t0);
    const Eigen::Vector3d a = position();
    until(t1);
    return (position() - a).head<2>() / (t1 - t0);
  }
};

HopperCommandKey key(double t, double vx, double vy, double heading = 0.0) {
  return HopperCommandKey{.t = t, .vx = vx, .vy = vy, .height = 1.05, .heading = heading};
}

TEST(HopperRun, RunsAlongXThenYThenDiagonallyThenStops) {
  HopperParams hp;
  const double d = std::sqrt(0.5);
  hp.script = {key(0.0, 0.0, 0.0), key(2.0, 1.0, 0.0), key(16.0, 0.0, 1.0), key(30.0, d, d), key(44.0, 0.0, 0.0)};
  Runner run(hp);
  struct Leg {
    const char* name;
    double t0, t1;
    Eigen::Vector2d command;
  };
  const Leg legs[] = {{"x", 6.0, 16.0, {1.0, 0.0}}, {"y", 20.0, 30.0, {0.0, 1.0}}, {"diagonal", 34.0, 44.0, {d, d}}};
  for (const Leg& leg : legs) {
    const Eigen::Vector2d v = run.meanVelocity(leg.t0, leg.t1);
    ASSERT_TRUE(run.world.ok()) << run.world.status();
    const double error = (v - leg.command).norm() / leg.command.norm();
    std::printf(
        "[ run %-8s ] command (%.3f, %.3f) m/s, mean over %.0f-%.0f s (%.4f, %.4f) m/s: speed %.4f m/s, "
        "vector error %.2f %%\n",
        leg.name, leg.command.x(), leg.command.y(), leg.t0, leg.t1, v.x(), v.y(), v.norm(), 100.0 * error);
    EXPECT_LT(error, 0.10) << leg.name;
  }
  // Stop: the command returns to zero at 44 s.
  const Eigen::Vector2d v_stop = run.meanVelocity(49.0, 52.0);
  ASSERT_TRUE(run.world.ok()) << run.world.status();
  std::printf("[ run stop     ] mean speed over 49-52 s %.4f m/s; max tilt over the run %.3f deg\n", v_stop.norm(),
              run.max_tilt * kRad);
  EXPECT_LT(v_stop.norm(), 0.05) << "it must come to a stop";
  EXPECT_LT(run.max_tilt * kRad, 15.0);
}

TEST(HopperRun, HeadingFollowsItsCommand) {
  HopperParams hp;
  hp.script = {key(0.0, 0.0, 0.0, 0.0), key(2.0, 0.0, 0.0, 90.0), key(8.0, 0.5, 0.0, -45.0)};
  Runner run(hp);
  run.until(7.5);
  ASSERT_TRUE(run.world.ok()) << run.world.status();
  const double yaw1 = run.hopper->attitude(run.world)[2] * kRad;
  run.until(14.0);
  ASSERT_TRUE(run.world.ok()) << run.world.status();
  const double yaw2 = run.hopper->attitude(run.world)[2] * kRad;
  std::printf("[ heading ] yaw %.2f deg (command 90), then %.2f deg (command -45, running 0.5 m/s); twist slips %d\n",
              yaw1, yaw2, run.hopper->contact().stats().twist_slips);
  EXPECT_NEAR(yaw1, 90.0, 5.0);
  EXPECT_NEAR(yaw2, -45.0, 5.0);
  EXPECT_LT(run.max_tilt * kRad, 15.0);
}

// The range of commanded speeds the hopper tracks within 10 % (mean over 8-14 s, the command
// ramped from rest at max_acceleration). Printed as a table; asserts the range documented in
// docs/HOPPER.md. Under the sanitizers three of the speeds, the range's asserted ends and its
// middle (50 s of the ASan run's time for the eight).
TEST(HopperRun, SpeedRangeThatTracksWithinTenPercent) {
  const std::vector<double> speeds = testing::fullOrSanitized(
      std::vector<double>{0.1, 0.25, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0}, std::vector<double>{0.25, 1.0, 2.0});
  double lowest = 1e9, highest = 0.0;
  bool contiguous = true, seen_bad_after_good = false;
  for (double s : speeds) {
    HopperParams hp;
    hp.command.vx = s;
    Runner run(hp);
    const Eigen::Vector2d v = run.meanVelocity(8.0, 14.0);
    const bool ok = run.world.ok() && run.max_tilt * kRad < 15.0;
    const double error = ok ? std::abs(v.x() - s) / s : 1e9;
    const bool tracks = ok && error < 0.10 && std::abs(v.y()) < 0.1 * s;
    std::printf("[ speed %.2f m/s ] mean %.4f m/s, error %6.2f %%, max tilt %.2f deg -> %s\n", s, ok ? v.x() : 0.0,
                ok ? 100.0 * error : 999.0, run.max_tilt * kRad, tracks ? "tracks" : "does not track");
    if (tracks) {
      if (seen_bad_after_good) contiguous = false;
      lowest = std::min(lowest, s);
      highest = std::max(highest, s);
    } else if (highest > 0.0) {
      seen_bad_after_good = true;
    }
  }
  std::printf("[ speed range ] tracks within 10 %% from %.2f to %.2f m/s%s\n", lowest, highest,
              contiguous ? "" : " (with gaps)");
  EXPECT_LE(lowest, 0.25);
  EXPECT_GE(highest, 2.0);
  EXPECT_TRUE(contiguous);
}

// The command changes while the hopper runs (the panel's velocity pad): setCommand keeps the state
// machine and its hop count, refuses an out-of-range command with the field named (and keeps the
// old one), and the new velocity is tracked.
TEST(HopperRun, SetCommandWhileRunning) {
  Runner run{HopperParams{}};
  run.until(3.0);
  const int hops = run.hopper->hops();
  ASSERT_GT(hops, 0);
  HopperCommand bad = run.hopper->params().command;
  bad.height = 99.0;
  const Status e = run.hopper->setCommand(bad);
  EXPECT_NE(e.message().find("hopper.command.height"), std::string::npos) << e.message();
  EXPECT_DOUBLE_EQ(run.hopper->params().command.height, HopperParams{}.command.height);
  HopperCommand go = run.hopper->params().command;
  go.vx = 0.8;
  EXPECT_TRUE(run.hopper->setCommand(go).ok());
  EXPECT_EQ(run.hopper->hops(), hops);  // nothing was rebuilt
  const Eigen::Vector2d v = run.meanVelocity(10.0, 14.0);
  EXPECT_NEAR(v.x(), 0.8, 0.08);
  EXPECT_NEAR(v.y(), 0.0, 0.08);
}

}  // namespace
}  // namespace ponyhop

// The hopper hops, headless, and is measured: hopping in place for 60 s (tilt, apex spread,
// drift, foot slip and sink, joint errors, no energy gained at touchdown), two height commands,
// and a sideways shove in flight. One run per scenario; every figure is printed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>

#include "common/physics_util.h"
#include "common/sanitizers.h"
#include "physics/models/hopper.h"

namespace ponyhop {
namespace {

using testing::kRad;

// A hopper in its own world (world.step() runs its Think first), with the measurements every test
// here needs.
struct HopRun : testing::HopperWorld {
  double max_tilt = 0.0, max_drift = 0.0, max_knee = 0.0, max_hip = 0.0;
  double max_slip = 0.0, min_foot_z = 1e9;
  std::vector<double> apex_time, apex;  // at each touchdown after the first: the flight's apex
  int touchdowns = 0;
  Eigen::Vector3d stance_start = Eigen::Vector3d::Zero();
  bool was_in_contact = false;

  explicit HopRun(const HopperParams& hp) : HopperWorld(hp) {}

  // Steps until time T; `each` runs before every step (perturbations).
  void until(double T, const std::function<void()>& each = {}) {
    const Eigen::Vector3d start(0.0, 0.0, 0.0);
    while (world.ok() && world.time() < T - 1e-9) {
      if (each) each();
      world.step();
      if (!world.ok()) break;
      const World& w = world;
      max_tilt = std::max(max_tilt, hopper->tilt(w));
      max_drift = std::max(max_drift, (body().x - start).head<2>().norm());
      max_knee = std::max(max_knee, hopper->kneeError(w));
      max_hip = std::max(max_hip, hopper->hipError(w));
      const Eigen::Vector3d foot = hopper->footPoint(w);
      min_foot_z = std::min(min_foot_z, foot.z());
      const bool contact = hopper->inContact();
      if (contact && !was_in_contact) {
        stance_start = foot;
        if (touchdowns++ > 0) {
          apex_time.push_back(w.time());
          apex.push_back(hopper->lastApex());
        }
      }
      if (contact) max_slip = std::max(max_slip, (foot - stance_start).head<2>().norm());
      was_in_contact = contact;
    }
  }
  // Apex heights recorded at touchdowns after time t0.
  std::vector<double> apexesAfter(double t0) const {
    std::vector<double> out;
    for (size_t i = 0; i < apex.size(); ++i) {
      if (apex_time[i] > t0) out.push_back(apex[i]);
    }
    return out;
  }
};

double spread(const std::vector<double>& v) {
  if (v.empty()) return 1e9;
  return *std::max_element(v.begin(), v.end()) - *std::min_element(v.begin(), v.end());
}
double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / v.size();
}

// Under the sanitizers the first 20 s (26 s of the ASan run's time for the minute), the hop counts
// bounded in proportion.
TEST(HopperHop, HopsInPlaceForAMinute) {
  HopperParams hp;                                  // defaults: command (0, 0), apex 1.05 m
  hp.velocity = Eigen::Vector3d(0.05, -0.05, 0.0);  // a small initial push: the controller must work
  HopRun run(hp);
  const double seconds = testing::fullOrSanitized(60.0, 20.0);
  run.until(seconds);
  ASSERT_TRUE(run.world.ok()) << run.world.status();
  const std::vector<double> apexes = run.apexesAfter(5.0);
  const ContactStats& cs = run.hopper->contact().stats();
  std::printf(
      "[ in place %.0f s ] hops %d, max tilt %.4f deg, apex mean %.4f m spread %.2e m (after 5 s, %zu hops), "
      "max drift %.2e m\n"
      "[ in place %.0f s ] stance slip %.2e m, lowest foot point %.2e m, knee |C| <= %.2e, hip |C| <= %.2e, "
      "touchdown kinetic energy change <= %.3f J, sliding touchdowns %d, slips %d\n",
      seconds, run.hopper->hops(), run.max_tilt * kRad, mean(apexes), spread(apexes), apexes.size(), run.max_drift,
      seconds, run.max_slip, run.min_foot_z, run.max_knee, run.max_hip, cs.max_touchdown_energy_gain,
      cs.sliding_touchdowns, cs.slips);
  EXPECT_GT(run.hopper->hops(), 1.5 * seconds) << "about one hop per 0.6 s";  // 90 in the minute
  EXPECT_LT(run.max_tilt * kRad, 15.0) << "the body must never fall";
  EXPECT_GT(apexes.size(), (seconds - 5.0) * 80.0 / 55.0);  // 80 after 5 s of the minute
  EXPECT_NEAR(mean(apexes), hp.command.height, 0.01);
  EXPECT_LT(spread(apexes), 0.005) << "apex height must be steady after the first seconds";
  EXPECT_LT(run.max_drift, 0.3);
  EXPECT_LT(run.max_slip, 1e-3) << "with mu = 1 the foot must not slip in stance";
  EXPECT_GT(run.min_foot_z, -2e-3) << "the foot must never sink more than 2 mm";
  EXPECT_LT(run.max_knee, 1e-9) << "the knee's five constraints";
  EXPECT_LT(run.max_hip, 1e-9) << "the hip joint";
  EXPECT_LE(cs.max_touchdown_energy_gain, 1e-9) << "a touchdown must never add kinetic energy";
}

// Apex heights for two commands: clearly different, each steady and close to its command.
TEST(HopperHop, HeightCommandsGiveDifferentSteadyApexes) {
  double means[2];
  const double heights[2] = {1.0, 1.2};
  for (int i = 0; i < 2; ++i) {
    HopperParams hp;
    hp.command.height = heights[i];
    HopRun run(hp);
    run.until(12.0);
    ASSERT_TRUE(run.world.ok()) << run.world.status();
    const std::vector<double> apexes = run.apexesAfter(6.0);
    means[i] = mean(apexes);
    std::printf("[ height %.2f m ] apex mean %.4f m, spread %.2e m over %zu hops (6-12 s), max tilt %.3f deg\n",
                heights[i], means[i], spread(apexes), apexes.size(), run.max_tilt * kRad);
    EXPECT_NEAR(means[i], heights[i], 0.01);
    EXPECT_LT(spread(apexes), 0.005);
    EXPECT_LT(run.max_tilt * kRad, 15.0);
  }
  EXPECT_GT(means[1] - means[0], 0.15) << "two commands must give clearly different apexes";
}

// A sideways shove in flight: 0.5 m/s added to the body (and the leg with it, so the joints stay
// consistent) while rising, after 6 s of hopping in place. Recovered: the horizontal speed back
// below 0.1 m/s (a fifth of the shove) at a touchdown, and staying there. Hops are counted as
// stances since the shove: the touchdown that ends the shoved flight has had none.
TEST(HopperHop, RecoversFromASidewaysShoveInFlight) {
  HopperParams hp;
  HopRun shoved(hp);
  shoved.until(6.0);
  bool pushed = false, was = shoved.hopper->inContact();
  int hops_at_push = 0;
  double push_time = 0.0;
  std::vector<double> speed_at_touchdown;  // horizontal speed at each touchdown after the push
  shoved.until(14.0, [&] {
    const bool now = shoved.hopper->inContact();
    if (pushed && now && !was) {
      speed_at_touchdown.push_back(shoved.hopper->centerOfMassVelocity(shoved.world).head<2>().norm());
    }
    was = now;
    if (pushed || shoved.hopper->phase() != HopperPhase::Flight || shoved.body().v.z() <= 0.0) return;
    const HopperModel& m = shoved.hopper->model();
    for (int i : {m.body, m.upper, m.foot}) shoved.world.body(i).v.y() += 0.5;
    pushed = true;
    hops_at_push = shoved.hopper->hops();
    push_time = shoved.world.time();
  });
  ASSERT_TRUE(pushed);
  ASSERT_TRUE(shoved.world.ok()) << shoved.world.status();
  int recovered_at = -1;
  for (size_t i = 0; i < speed_at_touchdown.size(); ++i) {
    bool stays = true;
    for (size_t j = i; j < speed_at_touchdown.size(); ++j) stays = stays && speed_at_touchdown[j] < 0.1;
    if (stays) {
      recovered_at = static_cast<int>(i);  // stances between the shove and this touchdown
      break;
    }
  }
  std::string list;
  for (double s : speed_at_touchdown) {
    // snprintf, not " " + std::to_string(s): GCC 12 at -O3 (Release) reports a false -Wrestrict
    // inside std::string's operator+ (GCC bug 105651) and -Werror stops the build.
    char buf[32];
    std::snprintf(buf, sizeof(buf), " %.3f", s);
    list += buf;
  }
  std::printf(
      "[ shove 0.5 m/s ] at t = %.3f s (hop %d); speed at the next touchdowns:%s m/s; recovered after %d hops; "
      "max tilt %.3f deg\n",
      push_time, hops_at_push, list.c_str(), recovered_at, shoved.max_tilt * kRad);
  EXPECT_GE(recovered_at, 1) << "a shove of 0.5 m/s must be visible at the first touchdown";
  EXPECT_LE(recovered_at, 5) << "recovered within five hops";
  EXPECT_LT(shoved.max_tilt * kRad, 15.0);
}

}  // namespace
}  // namespace ponyhop

// The hopper's converged reference (the bench's, bench/cmd_bench.cpp): with its controller thinking
// at the scene's 1 ms in every run and touchdowns located within the step, RK4 runs whose substeps
// differ by 2x agree within 1e-7 m over three stance phases. Without either they part: touchdowns
// taken at the end of a substep are up to a substep late, and a controller that thinks once per
// World step decides at different times when the step changes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/sanitizers.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

struct HopRun {
  std::vector<Eigen::Vector3d> body;  // every World step (1 ms)
  int stances = 0;
};

// The hopper scene for `seconds` with dense/rk4/projection, the World stepping `dt` in `substeps`.
HopRun hop(double dt, int substeps, const std::string& impact_tolerance, double seconds = 2.0) {
  Scene scene = loadScene("assets/scenes/hopper.json", {{"physics.solver", "dense"},
                                                        {"physics.integrator", "rk4"},
                                                        {"physics.stabilization", "projection"},
                                                        {"physics.dt", std::to_string(dt)},
                                                        {"physics.substeps", std::to_string(substeps)},
                                                        {"hopper.impact_tolerance", impact_tolerance}});
  Sim sim(scene);
  HopRun r;
  bool was = false;
  const long steps = std::lround(seconds / dt);
  for (long i = 0; i < steps && sim.ok(); ++i) {
    sim.step();
    r.body.push_back(sim.trackedPoint());
    const bool in = sim.hopper()->inContact();
    if (in && !was) ++r.stances;
    was = in;
  }
  EXPECT_TRUE(sim.ok()) << sim.status();
  return r;
}

// Time (s) until the two runs, sampled every `every` and `every_b` steps, first differ by more than
// 1e-7 m; 2 when they agree as far as both go.
double agreeFor(const HopRun& a, int every_a, const HopRun& b, int every_b, double sample) {
  for (size_t k = 0; k * every_a < a.body.size() && k * every_b < b.body.size(); ++k) {
    if ((a.body[k * every_a] - b.body[k * every_b]).norm() > 1e-7) return k * sample;
  }
  return 2.0;
}

// Under the sanitizers (104 s of the ASan run's time in full) each pair runs only as long as its
// measurement needs: the located and the late touchdowns through the third touchdown (1.29 s),
// 1.4 s; the controller at the step 0.1 s.
TEST(HopperReference, ConvergesOverThreeStancesWithAFixedControlRateAndLocatedTouchdowns) {
  const double seconds = testing::fullOrSanitized(2.0, 1.4);
  const HopRun a = hop(1e-3, 16, "1e-12", seconds), b = hop(1e-3, 32, "1e-12", seconds);
  const double located = agreeFor(a, 1, b, 1, 1e-3);
  // Touchdowns at the end of the step: the same controller, but an impact up to a substep late.
  // (Runs as long as the parting needs: they agree for 2 s when they do not part.)
  const HopRun c = hop(1e-3, 16, "0", std::min(seconds, 1.6)), d = hop(1e-3, 32, "0", std::min(seconds, 1.6));
  const double late = agreeFor(c, 1, d, 1, 1e-3);
  // The World's step halved instead: the controller thinks twice as often (its decisions move).
  const double think_seconds = testing::fullOrSanitized(0.6, 0.1);
  const HopRun e = hop(1.0 / 16000.0, 1, "1e-12", think_seconds), f = hop(1.0 / 32000.0, 1, "1e-12", think_seconds);
  const double think = agreeFor(e, 16, f, 32, 1e-3);
  // agreeFor's 2 means "as far as both went", which is the whole run here, not 2 s.
  const auto span = [](double t) {
    if (t >= 2.0) return std::string("the whole run");
    char text[32];
    std::snprintf(text, sizeof text, "%.3f s", t);
    return std::string(text);
  };
  std::printf(
      "[ reference ] %.1f s runs: 1/16 vs 1/32 ms substeps agree within 1e-7 m for %s (%d stances); touchdowns at "
      "the step's end: %s; the controller at the step: %s\n",
      seconds, span(located).c_str(), a.stances, span(late).c_str(), span(think).c_str());
  EXPECT_GE(a.stances, testing::fullOrSanitized(4, 3))
      << "2 s holds at least three whole stances (1.4 s three touchdowns)";
  EXPECT_GE(located, 2.0);
  EXPECT_LT(late, 1.9) << "without locating touchdowns the runs part within the three stances (at the third "
                          "touchdown, 1.29 s, when this test was written)";
  EXPECT_LT(think, 0.5) << "with the controller thinking at every step the runs part at once";
}

}  // namespace
}  // namespace ponyhop

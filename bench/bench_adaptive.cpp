#include "bench/bench_adaptive.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "bench/bench_report.h"
#include "physics/models/chain.h"

namespace ponyhop {
namespace {

// One run of a chain: the tip at every step, the energy drift, the CPU time of the steps.
struct AdaptiveRun {
  std::string variant;  // "full", "budget K", "tol X"
  int budget = 0;
  double tolerance = 0.0;
  std::vector<Eigen::Vector3d> tip;
  double drift = 0.0;                                    // J, max |E - E0| (fixed anchor)
  double cpu = std::numeric_limits<double>::infinity();  // s of CPU per simulated s, least of the repeats
  double active_mean = 0.0;
  int active_max = 0;
  double substeps = 0.0;  // mean substeps per dt (max_step_rotation splits a dt when the joints turn fast)
  double rotation = 2.0;  // max_step_rotation (deg): the reference takes a smaller one
  std::string stopped;    // the world's message when it stopped
};

// A chain of N links, 1 m long in all (hair to the waist), 0.2 kg; fixed: released from
// horizontal; shake: hanging from the shaking anchor. RK4 with the default automatic substeps
// (max_step_rotation): a reduced model concentrates the motion in its few active joints, which
// then turn faster than the full chain's (at a fixed 1/960 s without substeps the shaken 64-link
// chain ran away at budgets 4 to 16; the full one did not).
ChainWorld benchChain(int links, const std::string& anchor, double dt, int budget, double tolerance,
                      double max_step_rotation) {
  PhysicsParams pp;
  pp.dt = dt;
  pp.max_step_rotation = max_step_rotation;
  pp.solver = SolverKind::Featherstone;
  pp.integrator = Integrator::RK4;
  pp.adaptive_joints = budget;
  pp.adaptive_tolerance = tolerance;
  ChainParams cp;
  cp.links = links;
  cp.length = 1.0 / links;
  cp.radius = 0.3 * cp.length;
  cp.mass = 0.2 / links;
  cp.direction = anchor == "fixed" ? Eigen::Vector3d(1.0, 0.0, 0.0) : Eigen::Vector3d(0.0, 0.0, -1.0);
  AnchorParams ap;
  ap.motion = anchor == "fixed" ? AnchorMotion::Fixed : AnchorMotion::Shake;
  return makeChainWorld(pp, cp, ap);
}

void runOnce(int links, const std::string& anchor, const AdaptiveBenchOptions& o, AdaptiveRun& run, bool record) {
  ChainWorld cw = benchChain(links, anchor, 1.0 / o.dt_denominator, run.budget, run.tolerance, run.rotation);
  const long steps = std::lround(o.seconds * o.dt_denominator);
  const double e0 = cw.world.energy();
  std::vector<Eigen::Vector3d> tip;
  double drift = 0.0, active_sum = 0.0, substeps = 0.0;
  int active_max = 0;
  if (record) tip.reserve(steps);
  double cpu = 0.0;
  long done = 0;
  for (; done < steps && cw.world.ok(); ++done) {
    const double c0 = threadCpuSeconds();
    cw.world.step();
    cpu += threadCpuSeconds() - c0;
    if (!record) continue;
    tip.push_back(cw.chain.tip(cw.world));
    substeps += cw.world.lastSubsteps();
    drift = std::max(drift, std::abs(cw.world.energy() - e0));
    const int active = cw.world.reduced() ? cw.world.reduced()->activeJoints() : 0;
    active_sum += active;
    active_max = std::max(active_max, active);
  }
  if (!cw.world.ok()) run.stopped = cw.world.status();
  run.cpu = std::min(run.cpu, cpu / (static_cast<double>(done) / o.dt_denominator));
  if (record) {
    run.tip = std::move(tip);
    run.drift = drift;
    run.active_mean = done > 0 ? active_sum / static_cast<double>(done) : 0.0;
    run.active_max = active_max;
    run.substeps = done > 0 ? substeps / static_cast<double>(done) : 0.0;
  }
}

// RMS of the tip's distance between two runs over the steps [0, end), and the largest.
std::pair<double, double> tipGap(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b,
                                 size_t end) {
  double sum = 0.0, worst = 0.0;
  const size_t m = std::min({a.size(), b.size(), end});
  for (size_t i = 0; i < m; ++i) {
    const double e = (a[i] - b[i]).norm();
    sum += e * e;
    worst = std::max(worst, e);
  }
  return {m > 0 ? std::sqrt(sum / static_cast<double>(m)) : 0.0, worst};
}

// % of the chain's 1 m, two digits.
std::string percent(double metres) { return fmt(100.0 * metres, "%.2g") + " %"; }

}  // namespace

int runAdaptiveBench(const AdaptiveBenchOptions& o) {
  std::filesystem::create_directories(o.out);
  const std::string path = o.out + "/adaptive.md";
  std::ofstream md(path);
  if (!md) throw std::runtime_error(path + ": cannot write the file");
  const std::string load_before = loadAverage();
  md << "# Adaptive dynamics against the full step\n\n"
     << "Written by `" << o.command_line << "` (bench/bench_adaptive.cpp; the method: docs/SOLVERS.md, "
     << "\"Adaptive dynamics\").\n\n"
     << "A chain of N links, 1 m long in all and 0.2 kg, solver featherstone, RK4 at dt = 1/" << o.dt_denominator
     << " s with the default automatic substeps (max_step_rotation 2 deg), " << fmt(o.seconds, "%g")
     << " s simulated. fixed: released from horizontal (energy drift is meaningful); shake: hanging from the "
        "shaking anchor. Error: the tip's distance from the full run's tip at the same time (every dt), RMS over "
        "the first 0.5 s, the first 1 s and the whole run, and the largest over the whole run, in % of the chain's "
        "1 m. conv.: the same against a converged full run (max_step_rotation "
     << fmt(o.reference_rotation, "%g")
     << " deg, not timed; its row is the full run's own time-step error). Cost: CPU seconds of World::step per "
        "simulated second, the least of "
     << o.repeats
     << " runs, the variants of a case interleaved. Active joints: per step, mean and max. Substeps: per dt, mean.\n\n"
     << "Load average before: " << load_before << ".\n\n"
     << "| N | anchor | variant | RMS 0-0.5 s | RMS 0-1 s | RMS 0-" << fmt(o.seconds, "%g")
     << " s | max | conv. RMS 0-1 s | conv. RMS 0-" << fmt(o.seconds, "%g")
     << " s | energy drift (J) | CPU s per sim. s | full / this | active mean | active max | substeps |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  int status = 0;
  for (int n : o.links) {
    for (const std::string& anchor : o.anchors) {
      const auto variant = [](std::string name, int budget, double tolerance) {
        AdaptiveRun r;
        r.variant = std::move(name);
        r.budget = budget;
        r.tolerance = tolerance;
        return r;
      };
      std::vector<AdaptiveRun> runs{variant("full", 0, 0.0)};
      for (int b : o.budgets) {
        if (b < n) runs.push_back(variant("budget " + std::to_string(b), b, 0.0));
      }
      for (double t : o.tolerances) runs.push_back(variant("tol " + fmt(t, "%g") + " J", 0, t));
      for (int r = 0; r < o.repeats; ++r) {
        for (AdaptiveRun& run : runs) runOnce(n, anchor, o, run, r == 0);
      }
      AdaptiveRun reference = variant("converged", 0, 0.0);
      reference.rotation = o.reference_rotation;
      if (o.reference_rotation > 0.0) runOnce(n, anchor, o, reference, true);
      const AdaptiveRun& full = runs.front();
      const size_t half = static_cast<size_t>(std::lround(0.5 * o.dt_denominator));
      const size_t one = static_cast<size_t>(o.dt_denominator);
      const size_t all = std::numeric_limits<size_t>::max();
      for (const AdaptiveRun& run : runs) {
        const auto [rms_half, max_half] = tipGap(run.tip, full.tip, half);
        const auto [rms_one, max_one] = tipGap(run.tip, full.tip, one);
        const auto [rms, worst] = tipGap(run.tip, full.tip, all);
        const bool conv = !reference.tip.empty();
        const double conv_one = conv ? tipGap(run.tip, reference.tip, one).first : 0.0;
        const double conv_all = conv ? tipGap(run.tip, reference.tip, all).first : 0.0;
        md << "| " << n << " | " << anchor << " | " << run.variant << " | " << percent(rms_half) << " | "
           << percent(rms_one) << " | " << percent(rms) << " | " << percent(worst) << " | "
           << (conv ? percent(conv_one) : std::string("-")) << " | " << (conv ? percent(conv_all) : std::string("-"))
           << " | " << (anchor == "fixed" ? fmt(run.drift) : std::string("-")) << " | " << fmt(run.cpu) << " | "
           << fmt(full.cpu / run.cpu, "%.2f") << " | " << fmt(run.active_mean, "%.1f") << " | " << run.active_max
           << " | " << fmt(run.substeps, "%.2f") << " |";
        if (!run.stopped.empty()) {
          md << " stopped: " << run.stopped;
          status = 1;
        }
        md << "\n";
        std::fprintf(stderr,
                     "bench adaptive: N=%d %s %-14s rms %.3g / %.3g / %.3g m (0.5 s, 1 s, all), conv. %.3g / %.3g m, "
                     "%.3g cpu s/s, active %.1f/%d, substeps %.2f%s\n",
                     n, anchor.c_str(), run.variant.c_str(), rms_half, rms_one, rms, conv_one, conv_all, run.cpu,
                     run.active_mean, run.active_max, run.substeps, run.stopped.empty() ? "" : " (stopped)");
      }
      if (!reference.stopped.empty()) {
        md << "\nThe converged reference stopped: " << reference.stopped << "\n";
        status = 1;
      }
      md.flush();
    }
  }
  md << "\nLoad average after: " << loadAverage() << ".\n";
  std::fprintf(stderr, "bench: adaptive dynamics -> %s\n", path.c_str());
  return status;
}

}  // namespace ponyhop

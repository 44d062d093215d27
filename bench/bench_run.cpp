#include "bench/bench_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "physics/stage_times.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

constexpr double kDriftSample = 1.0 / 240.0;  // s, how often the long run samples energy, joints, speed

long stepsFor(double duration, double dt) { return std::lround(duration / dt); }

std::unique_ptr<Sim> build(const BenchCase& c, const Method& m, double dt) {
  std::vector<Override> o = c.overrides;
  for (Override& x : methodOverrides(m, dt, c.control_period)) o.push_back(std::move(x));
  return std::make_unique<Sim>(loadScene(c.scene, o));
}

// Samples of a run with step dt: every step when dt >= kBenchGrid, else every kBenchGrid.
long sampleEvery(double dt) { return std::max(1L, std::lround(kBenchGrid / dt)); }

}  // namespace

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string Method::name() const {
  std::string n = solver + "/" + integrator + "/" + stabilization;
  if (step == StepControl::Fixed) return n;
  n += "+" + stepName();
  if (step == StepControl::Auto && rotation != kDefaultStepRotation) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", rotation);
    n += b;
  }
  return n;
}

std::vector<Override> methodOverrides(const Method& m, double dt, double control_period) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", control_period > 0.0 ? control_period : dt);
  const long substeps = control_period > 0.0 ? std::max(1L, std::lround(control_period / dt)) : 1L;
  char tol[32], rotation[32];
  std::snprintf(tol, sizeof tol, "%.17g", kBenchTolerance);
  std::snprintf(rotation, sizeof rotation, "%.17g", m.step == StepControl::Auto ? m.rotation : 0.0);
  return {{"physics.solver", m.solver},
          {"physics.integrator", m.integrator},
          {"physics.stabilization", m.stabilization},
          {"physics.dt", buf},
          {"physics.substeps", std::to_string(substeps)},
          {"physics.max_step_rotation", rotation},
          {"physics.tolerance", m.step == StepControl::Tol ? tol : "0"}};
}

Trajectory simulateTrajectory(const BenchCase& c, const Method& m, double dt, double duration) {
  Trajectory t;
  const double ws = c.worldStep(dt);
  const long every = sampleEvery(ws);
  t.stride = every * ws;
  auto sim = build(c, m, dt);
  if (!sim->ok()) {
    t.status = sim->status();
    return t;
  }
  t.p.push_back(sim->trackedPoint());
  const long n = stepsFor(duration, ws);
  for (long i = 1; i <= n; ++i) {
    if (!sim->step()) {
      t.status = sim->status();
      return t;
    }
    if (i % every == 0) t.p.push_back(sim->trackedPoint());
  }
  return t;
}

std::array<double, 2> trajectoryError(const Trajectory& run, const Trajectory& ref, double horizon) {
  // Only the run's samples at the reference's sample times: with a step that does not divide
  // the reference's stride (1/100 s against 1/1920 s), sample k at k / 100 s is on the reference's
  // grid only every 5th sample (j = 19.2 k). Rounding the ratio (19) paired k / 100 s with
  // k / 101.05 s: 1/1000 s with RK4 showed 0.057 m for a 1e-7 m run.
  double sum = 0.0, worst = 0.0;
  long count = 0;
  for (size_t k = 0; k < run.p.size() && k * run.stride <= horizon + 1e-9; ++k) {
    const double at = k * run.stride / ref.stride;
    const double j = std::round(at);
    if (std::abs(at - j) > 1e-6) continue;  // between the reference's samples
    const size_t r = static_cast<size_t>(j);
    if (r >= ref.p.size()) break;
    const double e = (run.p[k] - ref.p[r]).norm();
    sum += e * e;
    worst = std::max(worst, e);
    ++count;
  }
  return {count ? std::sqrt(sum / count) : 0.0, worst};
}

RunResult benchRun(const BenchCase& c, const Method& m, double dt, double horizon, int repeats,
                   const Trajectory& reference) {
  RunResult r;
  const double ws = c.worldStep(dt);
  const long n = stepsFor(horizon, ws);
  const long every = sampleEvery(ws);
  r.steps = n;
  std::unique_ptr<Sim> first;
  Trajectory traj;
  traj.stride = every * ws;
  std::vector<double> per_step;
  std::vector<double> substeps;
  for (int rep = 0; rep < std::max(1, repeats); ++rep) {
    auto sim = build(c, m, dt);
    if (!sim->ok()) {
      r.status = "failed";
      r.reason = sim->status();
      return r;
    }
    if (rep == 0) traj.p.push_back(sim->trackedPoint());
    // Timed as `ponyhop sim` steps (and as the peers' steps are timed): without the per-stage
    // clock, whose reads were 8 % of the tree step at N = 8. The stage columns come from one more
    // run with it on (below).
    sim->world().setStageTiming(false);
    Clock::duration total{};
    long taken = 0, substep_sum = 0;
    for (long i = 1; i <= n; ++i) {
      const auto t0 = Clock::now();
      const bool ok = sim->step();
      total += Clock::now() - t0;
      ++taken;
      substep_sum += std::max(1, sim->world().lastSubsteps());
      if (!ok) break;
      if (rep == 0 && i % every == 0) traj.p.push_back(sim->trackedPoint());
    }
    per_step.push_back(durationSeconds(total) / static_cast<double>(std::max(1L, taken)));
    substeps.push_back(static_cast<double>(substep_sum) / std::max(1L, taken));
    if (!sim->ok()) {  // deterministic: every repeat would stop the same way
      r.status = "failed";
      r.reason = sim->status();
      r.steps = taken;
      break;
    }
    if (rep == 0) first = std::move(sim);
  }
  // Cost: the median repeat.
  const double med = median(per_step);
  size_t pick = 0;
  for (size_t i = 0; i < per_step.size(); ++i) {
    if (std::abs(per_step[i] - med) < std::abs(per_step[pick] - med)) pick = i;
  }
  // Per step of dt (a World step of a control period holds period / dt of them).
  const double per = dt / ws;
  r.us_per_step = 1e6 * med * per;
  r.us_per_sim_second = r.us_per_step / dt;
  r.substeps = substeps[pick] * per;
  // The stages: one more run of the same steps with the per-stage clock on (not in the cost);
  // other = that run's step time minus its stages (the clock's own reads included).
  {
    auto staged_sim = build(c, m, dt);
    staged_sim->world().resetStageTimes();
    Clock::duration total{};
    for (long i = 1; i <= r.steps; ++i) {
      const auto t0 = Clock::now();
      const bool ok = staged_sim->step();
      total += Clock::now() - t0;
      if (!ok) break;
    }
    const StageTimes& stages = staged_sim->world().stageTimes();
    double staged = 0.0;
    for (int s = 0; s < StageTimes::kCount; ++s) {
      r.stage_us[s] = 1e6 * stages.seconds[s] / std::max(1L, r.steps) * per;
      staged += r.stage_us[s];
    }
    r.other_us = std::max(0.0, 1e6 * durationSeconds(total) / std::max(1L, r.steps) * per - staged);
  }
  if (r.status != "ok") return r;
  const auto err = trajectoryError(traj, reference, horizon);
  r.err_rms = err[0];
  r.err_max = err[1];

  // Long run: the first repeat continued (untimed) to the long duration.
  Sim& sim = *first;
  r.tolerance_misses = sim.world().toleranceMisses();
  const long total_steps = stepsFor(c.long_duration, ws);
  const long sample = std::max(1L, std::lround(kDriftSample / ws));
  const double e0 = sim.chainEnergy();  // after the horizon: equal to the start's up to the drift so far
  auto fresh = build(c, m, dt);
  const double e_start = fresh->chainEnergy();
  fresh.reset();
  double drift = std::abs(e0 - e_start);
  const auto observe = [&] {
    r.joint_drift = std::max(r.joint_drift, sim.maxJointError());
    r.max_speed = std::max(r.max_speed, sim.trackedVelocity().norm());
    if (c.conservative) drift = std::max(drift, std::abs(sim.chainEnergy() - e_start));
  };
  observe();
  // A long run may cost at most kLongRunBudget times what its timed horizon's steps predict (plus
  // a few seconds): the tolerance mode's step doubling once split every substep of the whipping
  // chain to its deepest level (1/1024 of dt) and held the whole bench for many minutes in one row.
  const double budget = kLongRunBudget * med * static_cast<double>(total_steps - n) + kLongRunSlack;
  const double cpu0 = threadCpuSeconds();
  bool over_budget = false;
  for (long i = n + 1; i <= total_steps; ++i) {
    if (!sim.step()) break;
    if (i % sample == 0) {
      observe();
      if (threadCpuSeconds() - cpu0 > budget) {
        over_budget = true;
        break;
      }
    }
  }
  observe();
  r.long_reached = sim.time();
  if (c.conservative) {
    r.energy_drift = drift;
    r.energy_rel = std::abs(e_start) > 0.0 ? drift / std::abs(e_start) : drift;
  }
  if (over_budget) {
    char why[200];
    std::snprintf(why, sizeof why,
                  "%.3g s of CPU by t = %.3g s, over %g x what the timed horizon's steps predict for the whole long "
                  "run (%.3g s): its steps grew dearer as it went",
                  threadCpuSeconds() - cpu0, r.long_reached, kLongRunBudget, budget - kLongRunSlack);
    r.long_status = "over_budget";
    r.long_reason = why;
    return r;
  }
  if (!sim.ok()) {
    r.long_status = "stopped";
    r.long_reason = sim.status();
    return r;
  }
  // Bounded: joints held to a centimetre, the tracked point slower than 100 m/s (the released
  // chain's tip peaks at 13-17 m/s), energy within its own size (conservative), the hopper's
  // body between 0.2 m and 5 m high.
  char why[160] = "";
  if (r.joint_drift > 1e-2)
    std::snprintf(why, sizeof why, "joint error %.3g m > 1 cm", r.joint_drift);
  else if (r.max_speed > 100.0)
    std::snprintf(why, sizeof why, "speed %.3g m/s > 100 m/s", r.max_speed);
  else if (c.conservative && r.energy_rel > 1.0)
    std::snprintf(why, sizeof why, "energy drift %.3g x E0", r.energy_rel);
  else if (sim.hopper() && !(sim.trackedPoint().z() > 0.2 && sim.trackedPoint().z() < 5.0)) {
    std::snprintf(why, sizeof why, "hopper body at z = %.3g m (fell or flew off)", sim.trackedPoint().z());
  }
  if (why[0]) {
    r.long_status = "unbounded";
    r.long_reason = why;
  }
  return r;
}

double ScalingRow::us() const { return median(us_per_step); }

std::vector<Override> scalingOverrides(int links) {
  // The scene's own direction (horizontal): the chain swings from its first step.
  return {{"chain.links", std::to_string(links)}, {"anchor.motion", "fixed"}};
}

namespace {

class SimSubject final : public ScalingSubject {
 public:
  explicit SimSubject(std::unique_ptr<Sim> sim) : sim_(std::move(sim)) {
    // Timed as the peers' steps are, without the per-stage clock (its reads were 4-5 % of a tree
    // step at N = 8).
    sim_->world().setStageTiming(false);
  }
  bool step() override { return sim_->step(); }
  bool ok() override { return sim_->ok(); }
  double jointError() override { return sim_->maxJointError(); }
  std::string why() const override { return sim_->status(); }
  double time() const override { return sim_->time(); }

 private:
  std::unique_ptr<Sim> sim_;
};

}  // namespace

std::vector<ScalingConfig> ourScalingConfigs(const std::string& scene, const std::vector<std::string>& solvers) {
  struct Ours {
    Method m;
    const char* drift;
  };
  const Ours all[] = {
      {{"tree", "symplectic_euler", "projection"}, "projection"},
      {{"tree", "rattle", "projection"}, "RATTLE (the default integrator)"},
      {{"tree", "symplectic_euler", "none"}, "none: no drift control"},
      {{"dense", "symplectic_euler", "projection"}, "projection"},
      {{"dense", "rattle", "projection"}, "RATTLE (the default integrator)"},
      {{"dense", "symplectic_euler", "none"}, "none: no drift control"},
      {{"featherstone", "symplectic_euler", "none"}, "joint coordinates: no drift"},
  };
  std::vector<ScalingConfig> out;
  for (const Ours& o : all) {
    if (!solvers.empty() && std::find(solvers.begin(), solvers.end(), o.m.solver) == solvers.end()) continue;
    ScalingConfig c;
    c.name = o.m.name();
    c.drift = o.drift;
    c.make = [scene, m = o.m](int links, std::string& error) -> std::unique_ptr<ScalingSubject> {
      BenchCase bc;
      bc.scene = scene;
      bc.overrides = scalingOverrides(links);
      auto sim = build(bc, m, kBenchGrid);
      if (!sim->ok()) {
        error = sim->status();
        return nullptr;
      }
      return std::make_unique<SimSubject>(std::move(sim));
    };
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<ScalingRow> runScalingSweep(const std::vector<ScalingConfig>& configs, int links, int rounds,
                                        double seconds, double budget) {
  const long steps = std::max(1L, stepsFor(seconds, kBenchGrid));
  const long block = std::max(1L, std::lround(kDriftSample / kBenchGrid));  // joint error sampled between blocks
  std::vector<ScalingRow> rows(configs.size());
  for (size_t i = 0; i < configs.size(); ++i) {
    rows[i].config = configs[i].name;
    rows[i].drift = configs[i].drift;
    rows[i].peer = configs[i].peer;
    rows[i].links = links;
    rows[i].steps = steps;
  }
  for (int round = 0; round < std::max(1, rounds); ++round) {
    for (size_t k = 0; k < configs.size(); ++k) {
      const size_t i = round % 2 == 0 ? k : configs.size() - 1 - k;  // ABBA: every other round reversed
      ScalingRow& row = rows[i];
      if (row.status != "ok") continue;  // stopped or skipped in the first round: deterministic
      std::string error;
      auto subject = configs[i].make(links, error);
      if (!subject) {
        row.status = "cannot_run";
        row.reason = error;
        continue;
      }
      double cpu = 0.0;
      for (long done = 0; done < steps && row.status == "ok";) {
        // The first round's first step alone: it estimates the round's cost before a block of an
        // O(n^3) configuration at N = 1024 (seconds a step) is spent on it.
        const long n = round == 0 && done == 0 ? 1 : std::min(block - done % block, steps - done);
        const double t0 = threadCpuSeconds();
        bool ok = true;
        for (long s = 0; s < n && (ok = subject->step()); ++s) {
        }
        cpu += threadCpuSeconds() - t0;
        done += n;
        if (!ok || !subject->ok()) {
          row.status = "failed";
          row.reason = subject->why();
          break;
        }
        if (round == 0) {
          row.joint_error = std::max(row.joint_error, subject->jointError());
          if (done == 1 && cpu * steps > budget) {
            row.status = "skipped";
            char b[160];
            std::snprintf(b, sizeof b, "about %.3g s of CPU per round (%.3g us/step) > the budget %.3g s",
                          cpu / n * steps, 1e6 * cpu / n, budget);
            row.reason = b;
          }
        }
      }
      if (row.status == "ok") row.us_per_step.push_back(1e6 * cpu / steps);
    }
  }
  return rows;
}

}  // namespace ponyhop

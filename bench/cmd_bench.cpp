// `ponyhop bench [--quick] [--out DIR]`: speed against accuracy (docs/bench/README.md).
//
// For the canonical chain (N = 8 and 32, fixed and shaking anchor) and the hopper, every
// solver x integrator x stabilization (from EnumNames, so new ones appear by themselves) x dt:
//   accuracy: RMS and max distance of the tracked point (chain tip, hopper body) from a reference
//             the bench computes itself: reduced coordinates (featherstone) with RK4 at a step
//             halved until the trajectories at h and h/2 agree within 1e-7 m over the horizon;
//             the released chain is chaotic, so the horizon is where that holds (found, stated);
//   long runs: energy drift (fixed anchor), joint drift, whether the motion stays bounded;
//   cost:     microseconds per step and per simulated second (median of repeats), per stage.
// Scaling: cost per step for N = 2 ... 1024, in motion, ours and the peers interleaved. The peer engines whose modules
// were built (MuJoCo, Bullet, ODE, DART: bench/peer.h) run the chains (fixed and shaking anchor) and the scaling sweep
// beside them, with a table of ours / fastest peer per N. Writes CSV, Markdown and PNGs.
#include <sys/utsname.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <thread>
#include <type_traits>
#include <vector>

#include "bench/bench_adaptive.h"
#include "bench/bench_loops.h"
#include "bench/bench_peers.h"
#include "bench/bench_report.h"
#include "bench/bench_run.h"
#include "bench/commands.h"
#include "engine/asset_loader.h"
#include "physics/models/head_collisions.h"
#include "physics/physics_params.h"
#include "physics/stage_times.h"
#include "physics/validate.h"
#include "sim/data_dir.h"
#include "sim/grid_cache.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

constexpr double kConverged = 1e-7;  // m: reference at h and h/2 agree within this

struct BenchArgs {
  std::string out = "docs/bench";
  bool quick = false;
  std::string chain_scene = "assets/scenes/chain.json";
  std::string hopper_scene = "assets/scenes/hopper.json";
  bool hopper = true;
  bool chains = true;
  bool peers = true;
  double long_fixed = -1.0, long_shake = -1.0, long_hopper = -1.0;  // s, < 0: the mode's default
  int repeats = -1;
  std::vector<int> links, dts;       // empty: the mode's set
  std::vector<std::string> anchors;  // empty: fixed and shake
  std::vector<std::string> methods;  // empty: every method and peer; else only these names (bench.csv's)
  bool merge = false;                // the rows replace their own in OUT/bench.csv; the headline is rebuilt
  bool scaling = true;
  bool scaling_only = false;
  std::vector<int> scaling_links;            // empty: the mode's set
  std::vector<std::string> scaling_solvers;  // empty: every solver of ours
  double scaling_budget = -1.0;              // s of CPU per round of a configuration; < 0: the mode's
  int scaling_rounds = -1;                   // interleaved rounds; < 0: the mode's
  double scaling_seconds = -1.0;             // s of motion timed per round; < 0: the mode's
  bool collision = true;
  bool collision_only = false;
  std::string ponytail_scene = "assets/scenes/ponytail.json";
  bool adaptive_only = false;
  bool equal_accuracy_only = false;
  AdaptiveBenchOptions adaptive;
  bool loops_only = false;
  std::string command_line;
};

struct Config {
  std::vector<int> links;
  std::vector<std::string> anchors{"fixed", "shake"};
  std::vector<int> dt_denominators;  // dt = 1 / d
  double horizon_cap = 0.0;          // s, at most this much of the converged horizon is used
  double reference_span = 0.0;       // s, how far the reference runs (looking for its horizon)
  double reference_h0 = 0.0;         // s, the reference's first step
  double reference_h_min = 0.0;
  double long_fixed = 0.0, long_shake = 0.0, long_hopper = 0.0;  // s
  int repeats = 1;
  std::vector<int> scaling_links;
  double scaling_budget = 0.0;   // s of CPU per round of a configuration at most (else skipped at that N)
  int scaling_rounds = 1;        // interleaved rounds
  double scaling_seconds = 0.0;  // s of the swing timed per round
};

Config makeConfig(bool quick) {
  Config c;
  if (quick) {
    c.links = {8};
    c.dt_denominators = {120, 480};
    c.horizon_cap = 0.25;
    c.reference_span = 0.3;
    c.reference_h0 = 1.0 / 3840.0;
    c.reference_h_min = 1.0 / 15360.0;
    c.long_fixed = c.long_shake = c.long_hopper = 0.5;
    c.repeats = 1;
    c.scaling_links = {2, 8, 32};
    c.scaling_budget = 0.2;
    c.scaling_rounds = 2;
    c.scaling_seconds = 1.0 / 60.0;
  } else {
    c.links = {8, 32};
    c.dt_denominators = {60, 120, 240, 480, 960, 1920};
    c.horizon_cap = 1.0;
    c.reference_span = 2.5;
    c.reference_h0 = 1.0 / 7680.0;
    c.reference_h_min = 1.0 / 61440.0;
    c.long_fixed = 60.0;
    c.long_shake = 10.0;
    c.long_hopper = 10.0;
    c.repeats = 3;
    for (int n = 2; n <= 1024; n *= 2) c.scaling_links.push_back(n);
    c.scaling_budget = 3.0;
    c.scaling_rounds = 5;
    c.scaling_seconds = 0.25;
  }
  return c;
}

std::vector<Method> allMethods() {
  std::vector<Method> m;
  for (auto s : EnumNames<SolverKind>::names) {
    for (auto i : EnumNames<Integrator>::names) {
      for (auto st : EnumNames<Stabilization>::names) m.push_back({std::string(s), std::string(i), std::string(st)});
    }
  }
  // The step-control knobs on the defaults: ponyhop's default (RATTLE, 2 deg per substep) on both
  // multiplier solvers, reduced coordinates with the same rule, and error control.
  m.push_back({"dense", "rattle", "none", StepControl::Auto});
  m.push_back({"tree", "rattle", "none", StepControl::Auto});
  m.push_back({"featherstone", "rk4", "none", StepControl::Auto});
  m.push_back({"tree", "rattle", "none", StepControl::Tol});
  // Coarse accuracy, cheaply (what a user after 1-10 cm would pick): a looser rotation limit on
  // the methods that blow up at coarse fixed steps (the whipping tip), so that only the whip is
  // substepped.
  for (double deg : {5.0, 10.0, 20.0}) {
    m.push_back({"featherstone", "symplectic_euler", "none", StepControl::Auto, deg});
    m.push_back({"featherstone", "rk4", "none", StepControl::Auto, deg});
    m.push_back({"tree", "rattle", "none", StepControl::Auto, deg});
  }
  // More limits on the cheapest of them (featherstone RK4) for the 0.1 m level: 12 and 15 deg
  // between 10 (bounded on 32 links) and 20 (not: the 32-link chain runs away at 3-6 s), 30 and
  // 45 for 8 links, where a step of 1/30 s is accurate enough and only the whip needs splitting.
  for (double deg : {12.0, 15.0, 30.0, 45.0}) m.push_back({"featherstone", "rk4", "none", StepControl::Auto, deg});
  return m;
}

// What cannot run at all (not tried): reduced coordinates hold the joints by construction and
// take only the joint-space integrators.
std::string cannotRun(const Method& m) {
  if (m.solver == "featherstone" && m.stabilization != "none") {
    return "solver 'featherstone' works in joint coordinates: the joints hold by construction and there is no "
           "drift for stabilization '" +
           m.stabilization + "' to correct (run it with stabilization = none)";
  }
  PhysicsParams p;  // the combinations no solver can run are refused by validate(), as for a scene
  enumFromName(m.solver, p.solver);
  enumFromName(m.integrator, p.integrator);
  enumFromName(m.stabilization, p.stabilization);
  return validate(p).message();  // "" when it can
}

struct Reference {
  Method method;
  Trajectory trajectory;
  double h = 0.0;
  double horizon = 0.0;  // s, where h and h/2 agree within kConverged
  std::string note;
};

// Halves the reference step from h0 until the runs at h and h/2 agree within kConverged over at
// least `target` seconds (or h reaches h_min). The finer run is the reference.
Reference computeReference(const BenchCase& bench_case, const Config& cfg, double target,
                           std::vector<ReferenceCheck>& checks) {
  Reference ref;
  BenchCase c = bench_case;
  for (const Override& o : bench_case.reference_overrides) c.overrides.push_back(o);
  // With a control period, the reference's steps divide it: the period / 16 down to / 128.
  const double h0 = c.control_period > 0.0 ? c.control_period / 16.0 : cfg.reference_h0;
  const double h_min = c.control_period > 0.0 ? c.control_period / 128.0 : cfg.reference_h_min;
  ref.method = {"featherstone", "rk4", "none"};
  Trajectory a = simulateTrajectory(c, ref.method, h0, cfg.reference_span);
  if (a.p.size() < 2) {  // featherstone cannot express this scene (the hopper's contact)
    ref.note = "reduced coordinates cannot run this scene (" + a.status +
               "); the reference is maximal-coordinate dense/rk4/projection, converged the same way";
    ref.method = {"dense", "rk4", "projection"};
    a = simulateTrajectory(c, ref.method, h0, cfg.reference_span);
  }
  double h = h0;
  while (true) {
    std::fprintf(stderr, "bench: %s reference %s at h = 1/%.0f s\n", c.id.c_str(), ref.method.name().c_str(), 2.0 / h);
    Trajectory b = simulateTrajectory(c, ref.method, 0.5 * h, cfg.reference_span);
    const size_t n = std::min(a.p.size(), b.p.size());
    double horizon = 0.0, max_diff = 0.0;
    const double check_time = std::min(target, cfg.reference_span);
    bool within = true;
    for (size_t k = 0; k < n; ++k) {
      const double d = (a.p[k] - b.p[k]).norm();
      if (k * a.stride <= check_time + 1e-9) max_diff = std::max(max_diff, d);
      if (within && d <= kConverged)
        horizon = k * a.stride;
      else
        within = false;
    }
    std::string status = a.status.empty() ? b.status : a.status;
    checks.push_back({c.id, ref.method.name(), h, max_diff, check_time, horizon, status});
    ref.trajectory = std::move(b);
    ref.h = 0.5 * h;
    ref.horizon = horizon;
    if (horizon >= target - 1e-9 || 0.5 * h <= h_min * 1.0001) break;
    a = std::move(ref.trajectory);
    h *= 0.5;
  }
  return ref;
}

// The chain of a scene as the peer engines build it (bench/bench_peers.h).
PeerChain peerChainOf(const std::string& scene, const std::vector<Override>& overrides) {
  return peerChainOf(Sim(loadScene(scene, overrides)));
}

std::string dtName(double dt) { return "1/" + fmt(1.0 / dt, "%.0f"); }

// The bench's row for ponyhop's default: RATTLE on the tree solver with the 2 deg step rule.
constexpr const char* kDefaultMethod = "tree/rattle/none+auto";

// The report's first section: per case, which method to pick for what; then the methods that
// cannot run, once (they are left out of every table below).
void writeSummary(std::ofstream& f, const std::vector<std::unique_ptr<BenchCase>>& cases,
                  const std::vector<BenchRow>& rows) {
  f << "## Summary: which method for what\n\n"
    << "Over every dt of each case. *Fastest bounded*: the cheapest run that completed, stayed finite and "
       "passed the long run's bounds. *Best accuracy per cost*: the smallest RMS error x cost product (error in m "
       "times wall seconds per simulated second; a run ten times dearer must be more than ten times more "
       "accurate). *Default*: what a scene gets without settings ("
    << kDefaultMethod
    << " at dt = 1/240 s, "
       "ponyhop's 2 deg step control; the hopper: at its scene's 1 ms); its rank is by cost among the bounded "
       "runs.\n\n"
    << "| case | fastest bounded | best accuracy per cost | the default | default's cost rank |\n"
    << "|---|---|---|---|---|\n";
  const auto describe = [](const BenchRow& r) {
    return "`" + r.method + "` dt " + dtName(r.dt) + ": " + fmt(r.r.us_per_sim_second * 1e-3) + " ms/s, err " +
           fmt(r.r.err_rms) + " m";
  };
  for (const auto& c : cases) {
    const double default_dt = c->control_period > 0.0 ? c->control_period : 1.0 / 240.0;
    const BenchRow* fastest = nullptr;
    const BenchRow* best = nullptr;
    const BenchRow* def = nullptr;
    std::vector<double> costs;
    for (const auto& row : rows) {
      if (row.bench_case != c.get() || row.r.status != "ok") continue;
      const bool bounded = row.r.long_status == "ok";
      if (bounded) costs.push_back(row.r.us_per_sim_second);
      if (bounded && (!fastest || row.r.us_per_sim_second < fastest->r.us_per_sim_second)) fastest = &row;
      const double score = row.r.err_rms * row.r.us_per_sim_second;
      if (!best || score < best->r.err_rms * best->r.us_per_sim_second) best = &row;
      if (row.method == kDefaultMethod && std::abs(row.dt - default_dt) < 1e-12) def = &row;
    }
    std::string rank = "-";
    if (def && def->r.long_status == "ok") {
      const long below =
          std::count_if(costs.begin(), costs.end(), [&](double x) { return x < def->r.us_per_sim_second; });
      rank = std::to_string(below + 1) + " of " + std::to_string(costs.size());
    } else if (def) {
      rank = "not bounded: " + def->r.long_status;
    }
    f << "| " << c->title << " | " << (fastest ? describe(*fastest) : "none bounded") << " | "
      << (best ? describe(*best) : "none completed") << " | " << (def ? describe(*def) : "not run") << " | " << rank
      << " |\n";
  }
  std::map<std::string, std::string> cannot;  // method -> why, once
  for (const auto& row : rows) {
    if (row.r.status == "cannot_run") cannot.emplace(row.method, row.r.reason);
  }
  if (!cannot.empty()) {
    f << "\n**Cannot run** (by construction; left out of the tables below):\n\n";
    for (const auto& [method, why] : cannot) f << "- `" << method << "`: " << why << '\n';
  }
  f << '\n';
}

// The README's section after the headline (cost at equal accuracy): how the bench measures.
constexpr const char* kHowTitle = "\n## How the bench measures\n";
// The headline's source when rebuilt from bench.csv (--equal-accuracy-only, --merge).
constexpr const char* kMergedSource =
    "the bench.csv beside this README: the run named at the top, with the rows of the runs listed in merges.md "
    "(`--merge`, when there is one) in place of its own";

// "2026-11-28 17:40 UTC": when a merged run was made.
std::string utcNow() {
  const std::time_t t = std::time(nullptr);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%d %H:%M UTC", std::gmtime(&t));
  return b;
}

// Markdown: one table of methods at a dt, the Pareto front, per-stage costs.
void writeMarkdown(const std::string& path, const BenchArgs& args, const Config& cfg,
                   const std::vector<std::unique_ptr<BenchCase>>& cases, const std::vector<BenchRow>& rows,
                   const std::vector<Reference>& refs, const std::vector<ReferenceCheck>& checks,
                   const std::string& scaling_section, const std::vector<std::string>& notes,
                   const std::string& load_before, const std::string& load_after, double wall) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write the file");
  utsname u{};
  uname(&u);
  f << "# Bench: speed against accuracy\n\n"
    << "Made by `" << args.command_line << "` (" << (args.quick ? "quick mode" : "full") << ", " << fmt(wall, "%.0f")
    << " s wall) on " << u.nodename << " (" << u.machine << ", " << std::thread::hardware_concurrency()
    << " hardware threads); load average before " << load_before << ", after " << load_after
    << ". Timings on a shared, loaded machine are noisy upper bounds; compare methods within one run.\n";
  writeEqualAccuracySection(f, costPoints(rows), "this run (bench.csv)");
  f << kHowTitle << "\n"
    << "Files: `bench.csv` (every run, failed ones with the World's message), `reference.csv` (the "
       "reference's convergence check), `scaling.csv`, `error_vs_cost_*.png`, `scaling.png`.\n\n"
    << "Every run uses fixed steps (`physics.substeps = 1`, `max_step_rotation = 0`, `tolerance = 0`): dt "
       "means dt; except the rows marked `+auto` (`max_step_rotation = 2` deg: ponyhop's default step control), "
       "`+auto5` ... `+auto45` (the same control with a coarser limit, 5 to 45 deg per substep: coarse "
       "accuracy cheaply, only the whip substepped) and `+tol` (`tolerance = "
    << fmt(kBenchTolerance, "%g")
    << "` m, step doubling), whose cost per step includes "
       "their substeps (the substeps column: mean per dt). Cost: wall time of `Sim::step`, the step `ponyhop sim` "
       "takes, with the per-stage clock off as `ponyhop sim` runs it and as the peers' steps carry none; the stage "
       "columns come from one more run of the same steps with that clock on. Error: RMS and max distance of the "
       "tracked point (chain: "
       "the free end; hopper: the body "
       "centre) from the reference at the run's own steps over the converged horizon (those that fall on the "
       "reference's samples: every 1/1920 s on the chains, all of them for the dts that divide it). Long runs continue "
       "the "
       "first run untimed: energy drift max|E - E0| (fixed anchor, conservative), joint drift (max |C| sampled "
       "every 1/240 s) and bounded (joints within 1 cm, speed below 100 m/s, energy drift below E0, the hopper "
       "between 0.2 and 5 m high); a long run whose CPU time passes "
    << fmt(kLongRunBudget, "%g") << "x what its timed horizon's steps predict (plus " << fmt(kLongRunSlack, "%g")
    << " s) is stopped there, `over_budget` (not bounded). The hopper's runs step the World at its controller's period "
       "(the scene's "
       "dt, 1 ms: Think once per step) in 1 ms / dt fixed substeps of dt, so every run and the reference share one "
       "controller; its dt column is the substep and its costs are per substep.\n\n";
  for (const auto& n : notes) f << "- " << n << '\n';
  if (!notes.empty()) f << '\n';

  writeSummary(f, cases, rows);

  f << "## Reference and its horizon\n\n"
    << "| case | reference | h | h/2 | max tip difference over the check span | check span (s) | horizon within "
       "1e-7 m (s) |\n|---|---|---|---|---|---|---|\n";
  for (const auto& c : checks) {
    f << "| " << c.case_id << " | " << c.method << " | " << dtName(c.h) << " | " << dtName(0.5 * c.h) << " | "
      << fmt(c.max_diff) << " | " << fmt(c.check_time) << " | " << fmt(c.horizon) << " |\n";
  }
  f << "\nHorizon used for the error columns (the converged horizon, cut to a multiple of 1/60 s and at most "
    << fmt(cfg.horizon_cap) << " s; the hopper's at most 2 s, three stances):\n\n";
  for (size_t i = 0; i < refs.size(); ++i) {
    f << "- " << cases[i]->title << ": reference " << refs[i].method.name() << " at h = " << dtName(refs[i].h)
      << " s, converged for " << fmt(refs[i].horizon) << " s; error measured over ";
    double used = 0.0;
    for (const auto& r : rows) {
      if (r.bench_case == cases[i].get()) used = r.horizon;
    }
    f << fmt(used) << " s." << (refs[i].note.empty() ? "" : " " + refs[i].note) << '\n';
  }

  for (size_t ci = 0; ci < refs.size(); ++ci) {
    const BenchCase& c = *cases[ci];
    f << "\n## " << c.title << "\n\n![error against cost](error_vs_cost_" << c.id << ".png)\n\n";
    const double pick = !c.dt_denominators.empty() ? 1.0 / c.dt_denominators.front()
                        : args.quick               ? 1.0 / 480.0
                                                   : 1.0 / 240.0;
    f << "### All methods at dt = " << dtName(pick) << " s\n\n"
      << "| method | status | substeps | us/step | ms per sim. s | RMS err (m) | max err (m) | energy drift (J) | "
         "joint drift (m) "
         "| long run ("
      << fmt(c.long_duration) << " s) |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& row : rows) {
      if (row.bench_case != &c || std::abs(row.dt - pick) > 1e-12 || row.r.status == "cannot_run") continue;
      const RunResult& r = row.r;
      const bool ok = r.status == "ok";
      std::string why = r.reason;
      if (why.size() > 140) why = why.substr(0, 137) + "...";
      if (ok && r.tolerance_misses > 0) {
        why = "warning: " + std::to_string(r.tolerance_misses) +
              " substeps still above the tolerance at the deepest split (1/1024 of dt)";
      }
      f << "| " << row.method << " | " << r.status << (why.empty() ? "" : ": " + why) << " | "
        << (r.status == "cannot_run" ? "" : fmt(r.substeps, "%.3g")) << " | "
        << (r.status == "cannot_run" ? "" : fmt(r.us_per_step)) << " | "
        << (r.status == "cannot_run" ? "" : fmt(r.us_per_sim_second * 1e-3)) << " | " << (ok ? fmt(r.err_rms) : "")
        << " | " << (ok ? fmt(r.err_max) : "") << " | " << (ok && r.energy_drift >= 0 ? fmt(r.energy_drift) : "")
        << " | " << (ok ? fmt(r.joint_drift) : "") << " | "
        << (ok ? r.long_status + (r.long_status == "ok" ? "" : " at t = " + fmt(r.long_reached) + " s") : "") << " |\n";
    }
    f << "\n### Pareto front (no other run is both cheaper and more accurate)\n\n"
      << "| method | dt (s) | ms per sim. s | RMS err (m) | max err (m) |\n|---|---|---|---|---|\n";
    for (size_t i : paretoFront(rows, c.id)) {
      const auto& row = rows[i];
      f << "| " << row.method << " | " << dtName(row.dt) << " | " << fmt(row.r.us_per_sim_second * 1e-3) << " | "
        << fmt(row.r.err_rms) << " | " << fmt(row.r.err_max) << " |\n";
    }
    f << "\n### Cost of each stage (us per step, dt = " << dtName(pick) << " s, completed runs)\n\n| method |";
    for (auto n : StageTimes::names) f << ' ' << n << " |";
    f << " other |\n|---|";
    for (int s = 0; s <= StageTimes::kCount; ++s) f << "---|";
    f << '\n';
    for (const auto& row : rows) {
      if (row.bench_case != &c || std::abs(row.dt - pick) > 1e-12 || row.r.status != "ok") continue;
      if (row.stabilization == "-") continue;  // a peer engine: no stages
      f << "| " << row.method << " |";
      for (double v : row.r.stage_us) f << ' ' << fmt(v) << " |";
      f << ' ' << fmt(row.r.other_us) << " |\n";
    }
  }

  f << scaling_section;
}

// The cost of the ponytail's collisions: the demo scene (ponytail.json: the head collider, a swing
// cone at the root) stepped with its collision section and without it, per clip, the same steps.
// The machine is shared: a step's time is the thread's CPU time (a preempted bench is not
// charged), and the two are run in interleaved rounds (off, on, then on, off, ...), so that a
// change of load or clock speed meets both alike; each round's on / off ratio is kept, and the
// table gives the median over the rounds and their spread (smallest to largest).
struct CollisionCostRow {
  std::string clip;
  bool on = false;
  double build_s = 0.0;  // s, building the Sim (with collisions: the head's distance grid too)
  // CPU us per step of Sim::step, per round, with no stage clock read (on and off alike); the
  // contact stage (on: the stage clock on thread CPU, impulses and push-outs; the impact check's
  // searches and the splits are in the step, not here), from a further run of the round with that
  // clock read, and that run's whole step (the clock's own reads included: two a substep, each a
  // system call of about 0.2 us, which the ratio must not charge to the collider).
  std::vector<double> us_per_step, contact_us, timed_us;
  std::vector<double> ratio;  // on: per round, us_per_step / the same round's off
  int steps = 0;
  int max_contacts = 0;    // contacts and active limits after a step, at most
  double deepest = 0.0;    // m, deepest contact overlap a contact stage found (before pushing out)
  double overshoot = 0.0;  // rad, furthest a joint limit (the root cone) was passed at a contact stage
  // Per step, of the last round: distance-field evaluations, projected Gauss-Seidel sweeps; and
  // the solves that stopped at their sweep cap (CollisionStats).
  double queries = 0.0, sweeps = 0.0;
  long capped = 0;
  std::string status = "ok";
};

namespace {

// One run of a clip with the collider on or off into its row: the step's CPU time, the stage's.
// `stage_clock` (on only): the contact stage is timed, and the step goes to timed_us instead.
void runCollisionRound(const std::string& scene_path, double seconds, CollisionCostRow& r, bool stage_clock = false) {
  // Every round builds its grid, from the triangles: the build time is measured (neither the last
  // grid nor one stored by PONYHOP_GRID_CACHE, sim/grid_cache.h, once that has been looked up).
  useGridCacheFromEnvironment();
  setGridStore(nullptr);
  clearHeadColliderCache();
  Scene scene = loadScene(scene_path, {{"head.animation.clip", r.clip}});
  if (!r.on) scene.collision.reset();
  if (r.on && !scene.collision) scene.collision.emplace();
  const auto t0 = Clock::now();
  Sim sim(scene, &assimpAssets());
  r.build_s = std::max(r.build_s, std::chrono::duration<double>(Clock::now() - t0).count());
  // The contact stage on the step's clock, so that contact / rest compares two thread CPU times;
  // no other stage reads a clock. The runs the ratio compares read none (on and off alike).
  sim.world().setStageClock(StageClock::Source::ThreadCpu, StageClock::bit(Stage::Contact));
  if (!stage_clock) sim.world().setStageTiming(false);
  sim.world().resetStageTimes();
  r.steps = 0;
  const double c0 = threadCpuSeconds();
  while (sim.time() < seconds && sim.step()) {
    ++r.steps;
    if (const Collisions* c = sim.collisions()) {
      r.max_contacts = std::max(r.max_contacts, c->stats().active);
      r.deepest = std::max(r.deepest, c->stats().deepest);
      r.overshoot = std::max(r.overshoot, c->stats().overshoot);
    }
  }
  const double cpu = threadCpuSeconds() - c0;
  if (!sim.ok()) r.status = sim.status();
  if (const Collisions* c = sim.collisions()) {
    r.queries = static_cast<double>(c->stats().queries) / std::max(1, r.steps);
    r.sweeps = static_cast<double>(c->stats().sweeps) / std::max(1, r.steps);
    r.capped = c->stats().capped;
  }
  if (stage_clock) {
    r.timed_us.push_back(1e6 * cpu / std::max(1, r.steps));
    r.contact_us.push_back(1e6 * sim.world().stageTimes()[Stage::Contact] / std::max(1, r.steps));
  } else {
    r.us_per_step.push_back(1e6 * cpu / std::max(1, r.steps));
  }
}

// "median (smallest-largest)" of the values, each with `format`.
}  // namespace

std::vector<CollisionCostRow> benchCollisionCost(const std::string& scene_path, double seconds, int rounds) {
  std::vector<CollisionCostRow> rows;
  // snap: the stress clip, 4x the toss's peak angular speed (tests/engine/collision_head_test.cpp).
  for (const char* clip : {"showcase", "whip", "toss", "snap"}) {
    CollisionCostRow off, on;
    off.clip = on.clip = clip;
    on.on = true;
    for (int round = 0; round < std::max(1, rounds); ++round) {
      // Off first in even rounds, on first in odd ones (ABBA): a drift of the machine's speed
      // falls on both alike.
      runCollisionRound(scene_path, seconds, round % 2 ? on : off);
      runCollisionRound(scene_path, seconds, round % 2 ? off : on);
      on.ratio.push_back(on.us_per_step.back() / off.us_per_step.back());
      runCollisionRound(scene_path, seconds, on, true);  // the contact stage's share
    }
    for (const CollisionCostRow* r : {&off, &on}) {
      std::fprintf(stderr,
                   "bench: collision %-9s %-3s %9.1f us/step CPU (contact stage %.1f), on / off %s, %.0f queries, "
                   "%.1f sweeps per step, %ld capped, build %.2f s, %s\n",
                   clip, r->on ? "on" : "off", median(r->us_per_step), median(r->contact_us),
                   spreadOf(r->ratio, "%.2f").c_str(), r->queries, r->sweeps, r->capped, r->build_s, r->status.c_str());
    }
    rows.push_back(std::move(off));
    rows.push_back(std::move(on));
  }
  return rows;
}

void replaceSection(const std::string& path, const std::string& section, const std::string& insert_before);

// The section "Collision cost" of the README at `path` (at its end when new; a --collision-only run
// replaces only this section, up to the next level-2 title, and keeps the sections after it), and
// collision.csv beside it.
void appendCollisionCost(const std::string& path, const std::string& scene, double seconds, int rounds,
                         const std::vector<CollisionCostRow>& rows, const std::string& load_before,
                         const std::string& load_after) {
  constexpr const char* kTitle = "\n## Collision cost: the ponytail against its head\n";
  std::ostringstream f;
  f << kTitle << "\n"
    << "`" << scene << "` stepped for " << fmt(seconds, "%g")
    << " s of each clip with its `collision` section (on) and without it (off), the scene's own method, in "
    << std::max(1, rounds)
    << " interleaved rounds (off then on, on then off, ...). Per step: the CPU time of `Sim::step` (the thread's: a "
       "preempted bench is not charged) with no stage clock read on either side; the contact stage (impulses and "
       "push-outs; the impact check's searches and the substeps it splits are in the step, not in the stage) from a "
       "third run of each round with the stage clock on the same CPU clock (its reads, a system call each, are left "
       "out of the ratio); the "
       "median over the rounds and, in brackets, the smallest and largest. On / off: each round's ratio of the two "
       "(median and spread); contact / rest: the stage against the rest of the timed run's step (medians). Build: "
       "the slowest "
       "round's scene construction (on: the head's distance grid as well). Per step, of the last round: the "
       "distance-field evaluations of the narrow phase (queries) and the projected Gauss-Seidel sweeps (impulses and "
       "push-outs); capped: solves that stopped at their sweep cap before their tolerance. Deepest contact: the "
       "deepest overlap (mm, against the grid, margin included) a contact stage found before it pushed the links "
       "out; limit overshoot: the furthest (mrad) the root cone was passed there. Load average before / after: "
    << load_before << " / " << load_after << ".\n\n"
    << "| clip | collision | CPU us/step | contact stage us/step | on / off | contact / rest | build s | steps | "
       "queries/step | PGS sweeps/step | capped | max contacts | deepest contact (mm) | limit overshoot (mrad) | "
       "status |\n"
    << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const CollisionCostRow& r : rows) {
    const double step = r.timed_us.empty() ? 0.0 : median(r.timed_us), stage = median(r.contact_us);
    f << "| " << r.clip << " | " << (r.on ? "on" : "off") << " | " << spreadOf(r.us_per_step, "%.1f") << " | "
      << (r.on ? spreadOf(r.contact_us, "%.1f") : "") << " | " << (r.on ? spreadOf(r.ratio, "%.2f") : "") << " | "
      << (r.on && step > stage ? fmt(stage / (step - stage), "%.2f") : "") << " | " << fmt(r.build_s, "%.2f") << " | "
      << r.steps << " | " << (r.on ? fmt(r.queries, "%.0f") : "") << " | " << (r.on ? fmt(r.sweeps, "%.1f") : "")
      << " | " << (r.on ? std::to_string(r.capped) : "") << " | " << r.max_contacts << " | "
      << fmt(1e3 * r.deepest, "%.2f") << " | " << fmt(1e3 * r.overshoot, "%.2f") << " | " << r.status << " |\n";
  }
  replaceSection(path, f.str(), kTitle);
  std::ofstream csv(std::filesystem::path(path).parent_path() / "collision.csv");
  csv << "clip,collision,cpu_us_per_step,cpu_us_per_step_min,cpu_us_per_step_max,contact_us_per_step,on_off,"
         "on_off_min,on_off_max,build_s,steps,queries_per_step,sweeps_per_step,capped,max_contacts,deepest_m,"
         "overshoot_rad,status\n";
  for (const CollisionCostRow& r : rows) {
    const auto [lo, hi] = std::minmax_element(r.us_per_step.begin(), r.us_per_step.end());
    const bool ratios = !r.ratio.empty();
    csv << r.clip << ',' << (r.on ? "on" : "off") << ',' << median(r.us_per_step) << ',' << *lo << ',' << *hi << ','
        << median(r.contact_us) << ',' << (ratios ? median(r.ratio) : 0.0) << ','
        << (ratios ? *std::min_element(r.ratio.begin(), r.ratio.end()) : 0.0) << ','
        << (ratios ? *std::max_element(r.ratio.begin(), r.ratio.end()) : 0.0) << ',' << r.build_s << ',' << r.steps
        << ',' << r.queries << ',' << r.sweeps << ',' << r.capped << ',' << r.max_contacts << ',' << r.deepest << ','
        << r.overshoot << ',' << r.status << '\n';
  }
}

// Replaces the level-2 section of the README at `path` that `section` starts with (its first
// "## " line; up to the next level-2 title) by `section`, the rest kept; a section not there yet
// goes before the title `insert_before` (or at the end). A --scaling-only or --equal-accuracy-only
// run rewrites only its own.
void replaceSection(const std::string& path, const std::string& section, const std::string& insert_before) {
  std::string text;
  {
    std::ifstream in(path);
    std::stringstream b;
    b << in.rdbuf();
    text = b.str();
  }
  const size_t title_at = section.find("\n## ");
  const std::string title = section.substr(title_at, section.find('\n', title_at + 1) - title_at + 1);
  size_t from = text.find(title), to = std::string::npos;
  if (from != std::string::npos) {
    to = text.find("\n## ", from + 1);
  } else {
    from = to = text.find(insert_before);
  }
  if (from == std::string::npos) from = to = text.size();
  text = text.substr(0, from) + section + (to == std::string::npos ? "" : text.substr(to));
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write the file");
  out << text;
}

int runBench(BenchArgs& args) {
  const auto start = Clock::now();
  const std::string load_before = loadAverage();
  // From any folder: the scenes as given, else ponyhop's own (sim/data_dir.h).
  args.chain_scene = resolveSceneFile(args.chain_scene);
  args.hopper_scene = resolveSceneFile(args.hopper_scene);
  args.ponytail_scene = resolveSceneFile(args.ponytail_scene);
  Config cfg = makeConfig(args.quick);
  if (args.long_fixed >= 0.0) cfg.long_fixed = args.long_fixed;
  if (args.long_shake >= 0.0) cfg.long_shake = args.long_shake;
  if (args.long_hopper >= 0.0) cfg.long_hopper = args.long_hopper;
  if (args.repeats > 0) cfg.repeats = args.repeats;
  if (!args.links.empty()) cfg.links = args.links;
  if (!args.anchors.empty()) cfg.anchors = args.anchors;
  if (!args.dts.empty()) cfg.dt_denominators = args.dts;
  if (!args.scaling_links.empty()) cfg.scaling_links = args.scaling_links;
  if (args.scaling_budget >= 0.0) cfg.scaling_budget = args.scaling_budget;
  if (args.scaling_rounds > 0) cfg.scaling_rounds = args.scaling_rounds;
  if (args.scaling_seconds > 0.0) cfg.scaling_seconds = args.scaling_seconds;
  if (!args.scaling || args.merge) cfg.scaling_links.clear();  // a merge adds cases' rows only
  if (args.merge) args.collision = false;
  std::filesystem::create_directories(args.out);
  const double collision_seconds = args.quick ? 0.5 : 10.0;
  if (args.collision_only) {
    // Only the collision cost: its section of the README (the rest kept) and collision.csv.
    const std::vector<CollisionCostRow> rows = benchCollisionCost(args.ponytail_scene, collision_seconds, cfg.repeats);
    appendCollisionCost(args.out + "/README.md", args.ponytail_scene, collision_seconds, cfg.repeats, rows, load_before,
                        loadAverage());
    std::fprintf(stderr, "bench: collision cost -> %s/README.md\n", args.out.c_str());
    return 0;
  }
  if (args.equal_accuracy_only) {
    // Only the headline, from the bench.csv in the output folder: its section of the README.
    std::ostringstream section;
    writeEqualAccuracySection(section, readCostPoints(args.out + "/bench.csv"), kMergedSource);
    replaceSection(args.out + "/README.md", section.str(), kHowTitle);
    std::fprintf(stderr, "bench: cost at equal accuracy -> %s/README.md\n", args.out.c_str());
    return 0;
  }
  std::vector<std::string> notes;
  notes.push_back("Methods from EnumNames: solvers " + std::to_string(EnumNames<SolverKind>::names.size()) +
                  ", integrators " + std::to_string(EnumNames<Integrator>::names.size()) + ", stabilizations " +
                  std::to_string(EnumNames<Stabilization>::names.size()) + ".");

  std::vector<std::unique_ptr<BenchCase>> cases;
  if (!args.chains) cfg.links.clear();
  if (args.scaling_only) {
    cfg.links.clear();
    args.hopper = false;
  }
  for (int n : cfg.links) {
    for (const auto& a : cfg.anchors) {
      auto c = std::make_unique<BenchCase>();
      c->id = "chain" + std::to_string(n) + "_" + a;
      c->title = "chain N=" + std::to_string(n) + " " + a;
      c->scene = args.chain_scene;
      c->overrides = {{"chain.links", std::to_string(n)}, {"anchor.motion", a}};
      c->links = n;
      c->anchor = a;
      c->conservative = a == "fixed";
      c->long_duration = a == "fixed" ? cfg.long_fixed : cfg.long_shake;
      cases.push_back(std::move(c));
    }
  }
  if (args.hopper) {
    auto c = std::make_unique<BenchCase>();
    c->id = "hopper";
    c->title = "hopper";
    c->scene = args.hopper_scene;
    c->long_duration = cfg.long_hopper;
    // Think at the scene's rate (1 kHz) in every run; the runs' steps divide it. The reference
    // locates touchdowns to round-off depth and converges over three stances (2 s).
    c->control_period = loadScene(args.hopper_scene).physics.dt;
    for (int k : args.quick ? std::vector<int>{1, 4} : std::vector<int>{1, 2, 4, 8})
      c->dt_denominators.push_back(static_cast<int>(std::lround(k / c->control_period)));
    c->horizon_target = args.quick ? cfg.horizon_cap : 2.0;
    c->reference_overrides = {{"hopper.impact_tolerance", "1e-12"}};
    cases.push_back(std::move(c));
  }
  // Small cases first (the hopper right after N = 8): a stopped long bench keeps the cheap ones.
  std::stable_sort(cases.begin(), cases.end(), [](const auto& a, const auto& b) {
    return (a->links == 0 ? 8.5 : a->links) < (b->links == 0 ? 8.5 : b->links);
  });

  const PeerModules modules = args.peers ? loadPeerModules(peerModuleDirs()) : PeerModules{};
  const std::vector<Peer>& peers = modules.peers;
  if (args.peers) {
    for (const auto& n : modules.notes) notes.push_back(n);
  } else {
    notes.push_back("Peer engines left out (--no-peers).");
  }

  // Scaling first (short), then the cases; the files are rewritten after each case so that a
  // long run that is stopped early still leaves what it measured.
  // The sweep in motion, ours and the peers interleaved; one N at a time.
  std::vector<ScalingRow> scaling;
  std::string scaling_section;
  if (!cfg.scaling_links.empty()) {
    std::vector<ScalingConfig> configs = ourScalingConfigs(args.chain_scene, args.scaling_solvers);
    for (const Peer& peer : peers) configs.push_back(peerScalingConfig(peer, args.chain_scene));
    const std::string scaling_load = loadAverage();
    for (int n : cfg.scaling_links) {
      for (ScalingRow& r : runScalingSweep(configs, n, cfg.scaling_rounds, cfg.scaling_seconds, cfg.scaling_budget)) {
        std::fprintf(stderr, "bench: scaling %-34s N = %-5d %-28s us/step  joint error %.2g m  %s %s\n",
                     r.config.c_str(), n, spreadOf(r.us_per_step, "%.3g").c_str(), r.joint_error, r.status.c_str(),
                     r.reason.c_str());
        scaling.push_back(std::move(r));
      }
    }
    std::ostringstream section;
    writeScalingSection(section, scaling, buildFlagNotes(), cfg.scaling_rounds, cfg.scaling_seconds, args.command_line,
                        scaling_load, loadAverage());
    scaling_section = section.str();
  }
  if (args.scaling_only) {
    // Only the sweep: its files and its section of the README (the rest kept).
    writeScalingCsv(args.out + "/scaling.csv", scaling);
    if (std::string e = plotScaling(args.out, scaling); !e.empty()) std::fprintf(stderr, "bench: %s\n", e.c_str());
    replaceSection(args.out + "/README.md", scaling_section, "\n## Collision cost");
    std::fprintf(stderr, "bench: scaling -> %s/README.md\n", args.out.c_str());
    return 0;
  }

  std::vector<CollisionCostRow> collision_rows;
  std::string collision_load_before, collision_load_after;
  if (args.collision && !args.scaling_only) {
    collision_load_before = loadAverage();
    collision_rows = benchCollisionCost(args.ponytail_scene, collision_seconds, cfg.repeats);
    collision_load_after = loadAverage();
  }

  std::vector<BenchRow> rows;
  std::vector<Reference> refs;
  std::vector<ReferenceCheck> checks;
  const std::vector<Method> methods = allMethods();
  const auto wanted = [&](const std::string& name) {
    return args.methods.empty() || std::find(args.methods.begin(), args.methods.end(), name) != args.methods.end();
  };
  const auto writeAll = [&](size_t done) {
    if (args.merge) {
      // Only this run's rows into OUT/bench.csv and the headline rebuilt from it; the rest of the
      // README (the full run's tables) is left as that run wrote it. The run is logged beside it.
      const size_t replaced = mergeBenchCsv(args.out + "/bench.csv", rows);
      std::ostringstream section;
      writeEqualAccuracySection(section, readCostPoints(args.out + "/bench.csv"), kMergedSource);
      replaceSection(args.out + "/README.md", section.str(), kHowTitle);
      if (done == cases.size()) {
        std::ofstream log(args.out + "/merges.md", std::ios::app);
        log << "- `" << args.command_line << "`: " << rows.size() << " rows (" << replaced << " replaced), " << utcNow()
            << ", load average before " << load_before << ", after " << loadAverage() << "\n";
      }
      std::fprintf(stderr, "bench: %zu rows merged (%zu replaced) -> %s/bench.csv, README.md\n", rows.size(), replaced,
                   args.out.c_str());
      return;
    }
    std::vector<std::string> out_notes = notes;
    if (done < cases.size())
      out_notes.push_back("Partial: " + std::to_string(done) + " of " + std::to_string(cases.size()) +
                          " cases so far.");
    writeBenchCsv(args.out + "/bench.csv", rows);
    writeReferenceCsv(args.out + "/reference.csv", checks);
    writeScalingCsv(args.out + "/scaling.csv", scaling);
    for (size_t ci = 0; ci < done; ++ci) {
      const auto& c = cases[ci];
      if (std::string e = plotErrorVsCost(args.out, rows, *c); !e.empty())
        out_notes.push_back("plot " + c->id + ": " + e);
    }
    if (std::string e = scaling.empty() ? "" : plotScaling(args.out, scaling); !e.empty()) {
      out_notes.push_back("scaling plot: " + e);
    }
    for (const auto& n : out_notes) {
      if (n.rfind("plot", 0) == 0 || n.rfind("scaling plot", 0) == 0) std::fprintf(stderr, "bench: %s\n", n.c_str());
    }
    const double wall = std::chrono::duration<double>(Clock::now() - start).count();
    writeMarkdown(args.out + "/README.md", args, cfg, cases, rows, refs, checks, scaling_section, out_notes,
                  load_before, loadAverage(), wall);
    if (!collision_rows.empty()) {
      appendCollisionCost(args.out + "/README.md", args.ponytail_scene, collision_seconds, cfg.repeats, collision_rows,
                          collision_load_before, collision_load_after);
    }
    std::fprintf(stderr, "bench: %zu runs, %.0f s -> %s/README.md\n", rows.size(), wall, args.out.c_str());
  };
  for (const auto& cp : cases) {
    const BenchCase& c = *cp;
    const double cap = c.horizon_target > 0.0 ? c.horizon_target : cfg.horizon_cap;
    Reference ref = computeReference(c, cfg, std::min(cap, cfg.reference_span), checks);
    double horizon = std::floor(std::min(ref.horizon, cap) * 60.0 + 1e-9) / 60.0;
    if (horizon < 1.0 / 60.0) {
      notes.push_back(c.title + ": the reference converged for only " + fmt(ref.horizon) +
                      " s; errors are measured over 1/60 s and are not meaningful beyond it");
      horizon = 1.0 / 60.0;
    }
    for (int d : c.dt_denominators.empty() ? cfg.dt_denominators : c.dt_denominators) {
      const double dt = 1.0 / d;
      for (const Method& m : methods) {
        if (!wanted(m.name())) continue;
        BenchRow row{&c, m.name(), m.solver, m.integrator, m.stabilization, m.stepName(), dt, horizon, {}};
        if (std::string why = cannotRun(m); !why.empty()) {
          row.r.status = "cannot_run";
          row.r.reason = why;
        } else {
          row.r = benchRun(c, m, dt, horizon, cfg.repeats, ref.trajectory);
        }
        std::fprintf(stderr, "bench: %-14s %-40s dt 1/%-4d %-10s %9.1f us/step  err %.3g m%s%s\n", c.id.c_str(),
                     row.method.c_str(), d, row.r.status.c_str(), row.r.us_per_step, row.r.err_rms,
                     row.r.status == "ok" && row.r.long_status != "ok" ? "  long run: " : "",
                     row.r.status == "ok" && row.r.long_status != "ok" ? row.r.long_status.c_str() : "");
        rows.push_back(std::move(row));
      }
      if (!peers.empty() && c.links > 0) {
        const PeerChain chain = peerChainOf(c.scene, c.overrides);
        Sim sim(loadScene(c.scene, c.overrides));
        for (const Peer& peer : peers) {
          if (!wanted(peer.name)) continue;
          const auto slash = peer.name.find('/');
          BenchRow row{&c,      peer.name, peer.name.substr(0, slash), peer.name.substr(slash + 1), "-", "fixed", dt,
                       horizon, {}};
          row.r = benchPeerRun(peer, chain, dt, horizon, cfg.repeats, c.long_duration, ref.trajectory,
                               sim.chainEnergy(), c.conservative);
          std::fprintf(stderr, "bench: %-14s %-40s dt 1/%-4d %-10s %9.1f us/step  err %.3g m\n", c.id.c_str(),
                       row.method.c_str(), d, row.r.status.c_str(), row.r.us_per_step, row.r.err_rms);
          rows.push_back(std::move(row));
        }
      }
    }
    refs.push_back(std::move(ref));
    writeAll(refs.size());
  }
  if (cases.empty()) writeAll(0);
  return 0;
}

}  // namespace

CommandSpec benchCommand() {
  auto args = std::make_shared<BenchArgs>();
  CommandSpec cmd{"bench", "Speed against accuracy of every solver, integrator, stabilization and dt"};
  cmd.add("--out", args->out, "Output folder (CSV, README.md, PNG plots)");
  cmd.add("--quick", args->quick, "Smoke run: N = 8, two dts, short horizons, short scaling sweep (< 1 min)");
  cmd.add("--chain-scene", args->chain_scene, "The chain scene");
  cmd.add("--hopper-scene", args->hopper_scene, "The hopper scene");
  cmd.add("!--no-hopper", args->hopper, "Leave out the hopper");
  cmd.add("!--no-peers", args->peers, "Leave out the peer engines (MuJoCo, Bullet, ODE, DART when found)");
  cmd.add("--long-fixed", args->long_fixed, "Long run of the fixed-anchor chains, s (default 60; quick 0.5)")
      .within(0.0, 3600.0);
  cmd.add("--long-shake", args->long_shake, "Long run of the shaking-anchor chains, s (default 10; quick 0.5)")
      .within(0.0, 3600.0);
  cmd.add("--long-hopper", args->long_hopper, "Long run of the hopper, s (default 10; quick 0.5)").within(0.0, 3600.0);
  cmd.add("--repeats", args->repeats,
          "Timed repeats per run, the median is kept (default 3; quick 1); the collision cost: interleaved "
          "on/off rounds")
      .within(1, 100);
  cmd.add("--links", args->links, "Chain lengths to run, e.g. 8,32 (default 8,32; quick 8)").list().within(1, 4096);
  cmd.add("--anchors", args->anchors, "Anchor modes to run (default fixed,shake)").list().oneOf({"fixed", "shake"});
  cmd.add("--methods", args->methods,
          "Only these methods and peers, as bench.csv names them, e.g. "
          "featherstone/rk4/none+auto10,ode/worldstep (default all)")
      .list();
  cmd.add("--merge", args->merge,
          "Put this run's rows into OUT/bench.csv in place of the same case, method and dt (the rest kept), "
          "rebuild the headline of OUT/README.md from it and log the run in OUT/merges.md");
  cmd.add("--dts", args->dts, "Steps as 1/dt, e.g. 240,960 (default 60,120,240,480,960,1920; quick 120,480)")
      .list()
      .within(1, 100000);
  cmd.add("!--no-scaling", args->scaling, "Leave out the cost-against-N sweep");
  cmd.add("--scaling-only", args->scaling_only, "Only the cost-against-N sweep (no chains, no hopper)");
  cmd.add("!--no-chains", args->chains, "Leave out the chain cases (the hopper and the sweeps stay)");
  cmd.add("!--no-collision", args->collision,
          "Leave out the collision cost (the ponytail with its head collider on and off)");
  cmd.add("--ponytail-scene", args->ponytail_scene, "The scene of the collision cost");
  cmd.add("--collision-only", args->collision_only,
          "Only the collision cost: rewrites its section of OUT/README.md (the rest kept) and collision.csv");
  cmd.add("--scaling-links", args->scaling_links, "Chain lengths of the sweep (default 2,4,...,1024; quick 2..32)")
      .list()
      .within(1, 65536);
  cmd.add("--scaling-solvers", args->scaling_solvers,
          "Our solvers in the sweep, e.g. tree,featherstone (default all; for profiling one)")
      .list();
  cmd.add("--scaling-budget", args->scaling_budget,
          "CPU seconds a configuration's round of the sweep may take, else it is skipped at that N (default 3; "
          "quick 0.2)")
      .within(0.0, 3600.0);
  cmd.add("--scaling-rounds", args->scaling_rounds,
          "Interleaved rounds of the sweep, median and spread kept (default 5; quick 2)")
      .within(1, 100);
  cmd.add("--scaling-seconds", args->scaling_seconds,
          "Seconds of the swing timed per round of the sweep (default 0.25; quick 1/60)")
      .within(1e-3, 60.0);
  cmd.add("--equal-accuracy-only", args->equal_accuracy_only,
          "Only the headline, cost at equal accuracy, from OUT/bench.csv: rewrites its section of OUT/README.md");
  cmd.add("--adaptive-only", args->adaptive_only,
          "Only adaptive dynamics against the full step on long chains: writes OUT/adaptive.md");
  cmd.add("--adaptive-links", args->adaptive.links, "Chain lengths of --adaptive-only (default 64,256,1024)")
      .list()
      .within(2, 65536);
  cmd.add("--adaptive-budgets", args->adaptive.budgets, "Budgets of --adaptive-only (default 4,8,16,32,64)")
      .list()
      .within(1, 65536);
  cmd.add("--adaptive-seconds", args->adaptive.seconds, "Simulated seconds per run of --adaptive-only (2)")
      .within(0.01, 600.0);
  cmd.add("--adaptive-anchors", args->adaptive.anchors, "Anchors of --adaptive-only (default fixed,shake)")
      .list()
      .oneOf({"fixed", "shake"});
  cmd.add("--adaptive-tolerances", args->adaptive.tolerances,
          "Thresholds (J) of --adaptive-only's error form (default 1e-9,1e-7,1e-5; 0 = none)")
      .list()
      .within(0.0, 1e6);
  cmd.add("--adaptive-reference", args->adaptive.reference_rotation,
          "max_step_rotation (deg) of --adaptive-only's converged reference, not timed (0.5; 0 = none)")
      .within(0.0, 10.0);
  cmd.add("--adaptive-oracles", args->adaptive.oracles,
          "Diagnostic choices of --adaptive-only at each budget: acc, ref-speed, ref-fit, even, graded-P, "
          "chain (docs/bench/adaptive.md, \"Oracles\"; default none)")
      .list();
  cmd.add("--loops-only", args->loops_only,
          "Only closed loops (the four-bar, the hair loop): closure, energy, cost, agreement; writes "
          "OUT/loops.md (--dts, --repeats, --quick apply)");
  cmd.run = [args] {
    const auto list = [](const auto& v) {
      std::string s;
      for (const auto& x : v) {
        if (!s.empty()) s += ",";
        if constexpr (std::is_same_v<std::decay_t<decltype(x)>, std::string>)
          s += x;
        else if constexpr (std::is_floating_point_v<std::decay_t<decltype(x)>>)
          s += fmt(x, "%g");
        else
          s += std::to_string(x);
      }
      return s;
    };
    args->command_line = "ponyhop bench";
    if (args->quick) args->command_line += " --quick";
    args->command_line += " --out " + args->out;
    if (!args->hopper) args->command_line += " --no-hopper";
    if (!args->peers) args->command_line += " --no-peers";
    if (args->long_fixed >= 0.0) args->command_line += " --long-fixed " + fmt(args->long_fixed, "%g");
    if (args->long_shake >= 0.0) args->command_line += " --long-shake " + fmt(args->long_shake, "%g");
    if (args->long_hopper >= 0.0) args->command_line += " --long-hopper " + fmt(args->long_hopper, "%g");
    if (args->repeats > 0) args->command_line += " --repeats " + std::to_string(args->repeats);
    if (!args->links.empty()) args->command_line += " --links " + list(args->links);
    if (!args->anchors.empty()) args->command_line += " --anchors " + list(args->anchors);
    if (!args->dts.empty()) args->command_line += " --dts " + list(args->dts);
    if (!args->methods.empty()) args->command_line += " --methods " + list(args->methods);
    if (args->merge) args->command_line += " --merge";
    if (!args->scaling) args->command_line += " --no-scaling";
    if (args->scaling_only) args->command_line += " --scaling-only";
    if (!args->chains) args->command_line += " --no-chains";
    if (!args->collision) args->command_line += " --no-collision";
    if (args->collision_only) args->command_line += " --collision-only";
    if (args->ponytail_scene != BenchArgs{}.ponytail_scene)
      args->command_line += " --ponytail-scene " + args->ponytail_scene;
    if (!args->scaling_links.empty()) args->command_line += " --scaling-links " + list(args->scaling_links);
    if (!args->scaling_solvers.empty()) args->command_line += " --scaling-solvers " + list(args->scaling_solvers);
    if (args->scaling_budget >= 0.0) args->command_line += " --scaling-budget " + fmt(args->scaling_budget, "%g");
    if (args->scaling_rounds > 0) args->command_line += " --scaling-rounds " + std::to_string(args->scaling_rounds);
    if (args->scaling_seconds > 0.0) args->command_line += " --scaling-seconds " + fmt(args->scaling_seconds, "%g");
    try {
      if (args->adaptive_only) {
        AdaptiveBenchOptions& a = args->adaptive;
        a.out = args->out;
        if (args->repeats > 0) a.repeats = args->repeats;
        a.command_line = args->command_line + " --adaptive-only --adaptive-links " + list(a.links) +
                         " --adaptive-budgets " + list(a.budgets) + " --adaptive-seconds " + fmt(a.seconds, "%g") +
                         " --adaptive-anchors " + list(a.anchors) + " --adaptive-tolerances " + list(a.tolerances) +
                         " --adaptive-reference " + fmt(a.reference_rotation, "%g");
        if (!a.oracles.empty()) a.command_line += " --adaptive-oracles " + list(a.oracles);
        std::erase_if(a.tolerances, [](double t) { return t <= 0.0; });
        return runAdaptiveBench(a);
      }
      if (args->loops_only) {
        LoopBenchOptions l;
        l.out = args->out;
        l.peer_dirs = peerModuleDirs();
        if (args->quick) {
          l.four_bar_seconds = 1.0;
          l.hair_loop_seconds = 0.5;
          l.agree_dts = {240, 960};
          l.repeats = 1;
        }
        if (!args->dts.empty()) l.dts = args->dts;
        if (args->repeats > 0) l.repeats = args->repeats;
        l.command_line = args->command_line + " --loops-only";
        return runLoopBench(l);
      }
      return runBench(*args);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "ponyhop bench: %s\n", e.what());
      return 2;
    }
  };
  return cmd;
}

}  // namespace ponyhop

// The bench's measurements of one run (`ponyhop bench`, docs/bench/README.md): a scene file with
// overrides, stepped by Sim exactly as `ponyhop sim` steps it, timed step by step, its
// tracked point (the chain's tip, the hopper's body centre) sampled on a fixed time grid.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "physics/reflect.h"
#include "physics/stage_times.h"
#include "sim/scene_io.h"

namespace ponyhop {

// The time grid every trajectory is sampled on: 1/1920 s, the finest dt of the sweep, so that
// every dt of the sweep (1/60 ... 1/1920 s) and every reference step lands on it.
constexpr double kBenchGrid = 1.0 / 1920.0;

// One scene set-up of the bench: "chain N = 8, fixed anchor", "hopper".
struct BenchCase {
  std::string id;     // file-name safe: chain8_fixed
  std::string title;  // for tables: chain N=8 fixed
  std::string scene;  // scene file
  std::vector<Override> overrides;
  int links = 0;               // chain: links; hopper: 0
  std::string anchor;          // chain: fixed | shake; hopper: ""
  bool conservative = false;   // energy is conserved (fixed anchor, no damping): its drift is measured
  double long_duration = 0.0;  // s, the long run (drift, boundedness)
  // > 0: the scene's controllers think once per this period (s) whatever the step: every run
  // steps the World by it (physics.dt) in period / dt substeps of dt. The hopper's Think runs
  // at 1 kHz in every run, so runs and reference share one controller and differ only in their
  // integration (its decisions, taken once per World step, are otherwise up to a step late).
  double control_period = 0.0;
  std::vector<int> dt_denominators;           // this case's dts (1 / d s); empty: the bench's
  double horizon_target = 0.0;                // s, the reference must converge this long (0: the bench's cap)
  std::vector<Override> reference_overrides;  // added for the reference's runs only
  // The World's step of a run at dt.
  double worldStep(double dt) const { return control_period > 0.0 ? control_period : dt; }
};

// A position sampled every `stride` seconds from t = 0 (p[k] at k stride): every step of the run,
// or every kBenchGrid seconds when its steps are finer than that.
struct Trajectory {
  double stride = kBenchGrid;
  std::vector<Eigen::Vector3d> p;
  std::string status;  // "" when the run reached its end, else the World's message
  double duration() const { return p.empty() ? 0.0 : (p.size() - 1) * stride; }
};

// How a run chooses its step within each dt.
//   fixed: exactly one step of dt per World::step() (no automatic substeps, no error control)
//   auto:  ponyhop's default: substeps so that no body turns more than max_step_rotation = 2 deg
//   tol:   error control: step doubling keeps the per-step estimate below kBenchTolerance
enum class StepControl { Fixed, Auto, Tol };
constexpr double kBenchTolerance = 1e-5;  // m
template <>
struct EnumNames<StepControl> {
  static constexpr std::array<std::string_view, 3> names{"fixed", "auto", "tol"};
};

// The rotation limit of StepControl::Auto unless a method names its own: ponyhop's default.
constexpr double kDefaultStepRotation = 2.0;  // deg

// A scene's physics settings for one run.
struct Method {
  std::string solver, integrator, stabilization;
  StepControl step = StepControl::Fixed;
  // deg per substep (StepControl::Auto): a coarser limit than the default is part of the name
  // ("+auto10"), the choice of a user who wants a cheap, coarse and still bounded run.
  double rotation = kDefaultStepRotation;
  std::string stepName() const { return std::string(enumName(step)); }
  std::string name() const;
};

// The overrides that make a run use `method` at step dt: fixed steps (dt means dt), or dt split
// by the method's step control. With a control period: physics.dt = the period, in period / dt
// substeps.
std::vector<Override> methodOverrides(const Method& method, double dt, double control_period = 0.0);

// Runs the case with the method at dt for `duration` seconds and samples the tracked point.
Trajectory simulateTrajectory(const BenchCase& c, const Method& method, double dt, double duration);

// RMS and max distance of `run` from `reference` over run's samples in [0, horizon] that fall on
// the reference's samples (every one when the reference's stride divides run's). Returns {rms, max}.
std::array<double, 2> trajectoryError(const Trajectory& run, const Trajectory& reference, double horizon);

// The long run stops when its CPU time passes kLongRunBudget x the timed horizon's cost per step
// x its steps + kLongRunSlack (long_status "over_budget").
constexpr double kLongRunBudget = 10.0;
constexpr double kLongRunSlack = 5.0;  // s

struct RunResult {
  std::string status = "ok";  // ok | failed | cannot_run
  std::string reason;         // the World's status message or why it cannot run
  long steps = 0;             // steps in the timed horizon run
  double us_per_step = 0.0;   // median over repeats
  double us_per_sim_second = 0.0;
  // Per step, from one more run with the per-stage clock on (the timed repeats run without it).
  std::array<double, StageTimes::kCount> stage_us{};
  double other_us = 0.0;                // per step: that run's step() minus its stages
  double substeps = 1.0;                // mean World::lastSubsteps()
  int tolerance_misses = 0;             // +tol: substeps still above the tolerance at the deepest split (timed run)
  double err_rms = 0.0, err_max = 0.0;  // m, against the reference over the horizon
  // Long run (continues the first repeat to BenchCase::long_duration).
  std::string long_status = "ok";  // ok | stopped | unbounded | over_budget | skipped
  std::string long_reason;
  double long_reached = 0.0;   // s, simulated before it stopped
  double energy_drift = -1.0;  // J, max |E - E0| (conservative cases), -1: not applicable
  double energy_rel = -1.0;    // energy_drift / |E0| (E0 against the hanging reference)
  double joint_drift = 0.0;    // m, max joint error sampled every 1/240 s
  double max_speed = 0.0;      // m/s, the tracked point's largest speed (sampled every 1/240 s)
};

// The timed run: `repeats` runs of [0, horizon] (cost = median), the error against the
// reference, then the first repeat continued to the case's long duration.
RunResult benchRun(const BenchCase& c, const Method& method, double dt, double horizon, int repeats,
                   const Trajectory& reference);

// The scaling sweep (docs/bench/README.md, "Scaling"): cost per step against chain length, in
// motion. The chain of `links` links is released horizontally from a fixed anchor (the bench's
// fixed-anchor case) and every configuration, ours and the peers', is timed over the same first
// `seconds` of its swing at dt = kBenchGrid. The configurations run in interleaved rounds (in
// order, then in reverse order: ABBA), so that a change of load or clock speed meets all alike;
// a step's cost is the thread's CPU time (a preempted bench is not charged).

// One chain of the sweep, stepped in place.
class ScalingSubject {
 public:
  virtual ~ScalingSubject() = default;
  virtual bool step() = 0;          // false when the run stopped (why())
  virtual bool ok() = 0;            // still running, checked between timed blocks (a peer: finite)
  virtual double jointError() = 0;  // m, the largest gap of a joint now
  virtual std::string why() const = 0;
  virtual double time() const = 0;  // s, simulated
};

// A configuration of the sweep: one of ours (a Method) or a peer engine.
struct ScalingConfig {
  std::string name;   // tree/symplectic_euler/projection, mujoco/RK4
  std::string drift;  // how its joints are held: "projection", "none: no drift control", ...
  bool peer = false;
  // A fresh chain of `links` links at t = 0; nullptr with `error` set when it cannot be built.
  std::function<std::unique_ptr<ScalingSubject>(int links, std::string& error)> make;
};

// One configuration at one N over the rounds.
struct ScalingRow {
  std::string config, drift;
  bool peer = false;
  int links = 0;
  std::string status = "ok";  // ok | failed (stopped within the timed run) | skipped (over the budget) | cannot_run
  std::string reason;
  long steps = 0;                   // per round
  std::vector<double> us_per_step;  // CPU, one per round, in round order
  double joint_error = 0.0;         // m, largest over the timed run (sampled every 1/240 s)
  double us() const;                // the median round (0 when none)
};

// Our configurations of the sweep: per solver its drift control as shipped (tree and dense:
// projection, and RATTLE, the default integrator; featherstone: joint coordinates, no drift),
// plus symplectic Euler without stabilization (tree, dense), labelled as such. `solvers`: only
// these (empty: all).
std::vector<ScalingConfig> ourScalingConfigs(const std::string& scene, const std::vector<std::string>& solvers);

// The sweep at one N: `rounds` interleaved rounds of every configuration, each over the first
// `seconds` of the swing. A configuration whose first round would take more than `budget` s of
// CPU (estimated from its first step) is skipped at this N; one that stops is not repeated.
std::vector<ScalingRow> runScalingSweep(const std::vector<ScalingConfig>& configs, int links, int rounds,
                                        double seconds, double budget);

// The sweep's chain: `links` links released horizontally from the fixed anchor.
std::vector<Override> scalingOverrides(int links);

double median(std::vector<double> v);

}  // namespace ponyhop

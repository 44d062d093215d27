// `ponyhop sim SCENE [--duration T] [--set key=value]... [--csv FILE] [--poses FILE [--rate HZ | --at T,...]]`:
// the physics alone (no GL).
// --csv: a summary, one row per millisecond of simulated time; a row takes the step nearest to its
// time (values are held between steps).
// --poses: every body's pose and velocity, one row per body per step, or at exactly the times
// asked for (--rate, --at), interpolated between the two steps around each (app/pose_sampling.h).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <utility>

#include "app/commands.h"
#include "app/output_safety.h"
#include "app/pose_sampling.h"
#include "app/scene_args.h"
#include "engine/asset_loader.h"
#include "physics/stage_times.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

struct SimArgs {
  SceneArgs scene;
  double duration = -1.0;
  std::string csv;
  std::string poses;
  double rate = 0.0;
  std::vector<double> at;
};

// The values written for one state; columns depend on what the scene has. A hopper scene's
// phase column is text; it sits after the first `split` values.
struct SimRow {
  std::vector<double> values;
  std::string text;
  size_t split = 0;
};

std::string baseHeader(const Sim& sim) {
  // Hopper: body centre of mass (m, m/s), attitude (rad), leg length (m), phase, foot contact
  // point (m), contact 0/1, the largest violation of the knee's five constraints.
  if (sim.hopper()) {
    return "t,x,y,z,vx,vy,vz,roll,pitch,yaw,leg_length,phase,foot_x,foot_y,foot_z,contact,knee_error";
  }
  if (sim.chain()) return "t,tip_x,tip_y,tip_z,energy,max_joint_error";
  return "t,max_joint_error";
}

// A scene with collisions adds the active contacts and limits after the last contact stage, the
// deepest contact overlap (m) that stage found before it pushed the bodies apart, the furthest a
// joint limit was passed there (rad), its projected Gauss-Seidel sweeps (impulses and push-outs)
// and the solves stopped at their sweep cap so far.
// Adaptive dynamics on (physics.adaptive_joints or adaptive_tolerance) adds the joints that
// moved in the step (docs/SOLVERS.md).
bool adaptive(const Sim& sim) {
  const PhysicsParams& p = sim.world().params();
  return sim.world().reduced() && (p.adaptive_joints > 0 || p.adaptive_tolerance > 0.0);
}

std::string header(const Sim& sim) {
  return baseHeader(sim) + (sim.collisions() ? ",contacts,deepest,limit_overshoot,pgs_sweeps,pgs_capped" : "") +
         (adaptive(sim) ? ",active_joints" : "");
}

// Into `r`, reusing its storage (a row sampled at every step allocates nothing once sized).
void baseSampleInto(const Sim& sim, SimRow& r) {
  if (const Hopper* h = sim.hopper()) {
    const World& w = sim.world();
    const RigidBody& b = w.body(h->model().body);
    const Eigen::Vector3d att = h->attitude(w);
    const Eigen::Vector3d foot = h->footPoint(w);
    r.values = {b.x.x(),        b.x.y(), b.x.z(),          b.v.x(),  b.v.y(),  b.v.z(),  att[0],
                att[1],         att[2],  h->leg(w).length, foot.x(), foot.y(), foot.z(), h->inContact() ? 1.0 : 0.0,
                h->kneeError(w)};
    r.text = h->phaseName();
    r.split = 10;
  } else if (const Chain* c = sim.chain()) {
    const Eigen::Vector3d tip = c->tip(sim.world());
    r.values = {tip.x(), tip.y(), tip.z(), sim.chainEnergy(), sim.maxJointError()};
  } else {
    r.values = {sim.maxJointError()};
  }
}

void sampleInto(const Sim& sim, SimRow& r) {
  baseSampleInto(sim, r);
  if (const Collisions* c = sim.collisions()) {
    r.values.push_back(c->stats().active);
    r.values.push_back(c->stats().deepest);
    r.values.push_back(c->stats().overshoot);
    r.values.push_back(c->stats().iterations);
    r.values.push_back(static_cast<double>(c->stats().capped));
  }
  if (adaptive(sim)) r.values.push_back(sim.world().reduced()->activeJoints());
}

void writeRow(std::FILE* f, double t, const SimRow& r) {
  std::fprintf(f, "%.3f", t);
  for (size_t i = 0; i < r.values.size(); ++i) {
    if (!r.text.empty() && i == r.split) std::fprintf(f, ",%s", r.text.c_str());
    std::fprintf(f, ",%.9g", r.values[i]);
  }
  std::fputc('\n', f);
}

// Tolerance mode: the error estimated against what was asked, and the substeps that missed
// their share even at the deepest split.
void reportTolerance(const Sim& sim, const Scene& scene) {
  const double tolerance = scene.physics.tolerance;
  if (!(tolerance > 0.0)) return;
  std::fprintf(stderr, "sim: physics.tolerance %g m per simulated second: estimated error %.3g m after %.3f s\n",
               tolerance, sim.world().errorEstimateSum(), sim.time());
  if (const int misses = sim.world().toleranceMisses(); misses > 0) {
    std::fprintf(stderr,
                 "sim: warning: %d substeps kept an error estimate above their share of physics.tolerance = %g "
                 "m even at the deepest split (1/1024 of dt): the tolerance was not met there\n",
                 misses, tolerance);
  }
}

int runSummary(const Scene& scene, double duration, const SimArgs& args) {
  Sim sim(scene, &assimpAssets());
  sim.world().setStageTiming(false);  // nothing here reads the stage times: the step the bench times

  // Written to a temporary name and renamed: a failed run never replaces a good CSV.
  const std::string tmp = args.csv + ".partial-" + std::to_string(getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) throw InputError("--csv " + args.csv + ": cannot write the file");
  std::fprintf(f, "%s\n", header(sim).c_str());

  const long rows = static_cast<long>(std::floor(duration * 1000.0 + 1e-9)) + 1;
  long next = 0;  // next row (millisecond) to write
  double prev_t = sim.time();
  // A row takes the nearer of the two steps around its time, so a step's values (energy, joint
  // error: O(N) each) are read only when a row may take them: a row due by this step that is
  // nearer to it than to the last one, or one due before the middle of the next step (taken dt
  // later; the margin covers the rounding of the world's time). Steps finer than the rows
  // (dt 1/1920 against 1 ms) are not all read.
  const double half_step = 0.5 * scene.physics.dt * (1.0 + 1e-6);
  SimRow prev, cur;
  sampleInto(sim, prev);
  bool have_prev = true;
  writeRow(f, 0.0, prev);
  next = 1;
  // Progress on long runs: a line every 5 s of wall time (a long chain on a slow solver shows
  // its pace instead of silence).
  const auto t_start = Clock::now();
  auto t_report = t_start + std::chrono::seconds(5);
  while (next < rows) {
    if (const int sig = InterruptGuard::signal()) {
      std::fclose(f);
      std::remove(tmp.c_str());
      std::fprintf(stderr, "ponyhop sim: stopped by %s; %s was not written\n", sig == SIGINT ? "SIGINT" : "SIGTERM",
                   args.csv.c_str());
      return InterruptGuard::exitCode(sig);
    }
    if (Clock::now() >= t_report) {
      t_report += std::chrono::seconds(5);
      const double wall = std::chrono::duration<double>(Clock::now() - t_start).count();
      const double done = sim.time() / std::max(duration, 1e-12);
      std::fprintf(stderr, "sim: %.3f of %.3f s simulated (%.1f%%), %.0f s elapsed, about %.0f s left\n", sim.time(),
                   duration, 100.0 * done, wall, done > 0.0 ? wall * (1.0 - done) / done : 0.0);
    }
    if (!sim.step()) {
      std::fclose(f);
      std::remove(tmp.c_str());
      std::fprintf(stderr, "ponyhop sim: the simulation stopped: %s\n  %s was not written\n", sim.status().c_str(),
                   args.csv.c_str());
      return 1;
    }
    const double t = sim.time();
    bool have_cur = false;
    // Rows in (prev_t, t]: take whichever step is nearer.
    while (next < rows && next * 1e-3 <= t + 1e-12) {
      const double tr = next * 1e-3;
      const bool take_prev = (tr - prev_t) < (t - tr);
      if (take_prev && !have_prev) throw std::logic_error("sim --csv: a row took a step that was not read");
      if (!take_prev && !have_cur) {
        sampleInto(sim, cur);
        have_cur = true;
      }
      writeRow(f, tr, take_prev ? prev : cur);
      ++next;
    }
    if (!have_cur && next < rows && next * 1e-3 < t + half_step) {
      sampleInto(sim, cur);
      have_cur = true;
    }
    prev_t = t;
    std::swap(prev, cur);
    have_prev = have_cur;
  }
  const bool ok = std::fflush(f) == 0 && !std::ferror(f);
  std::fclose(f);
  std::error_code ec;
  if (!ok) {
    std::remove(tmp.c_str());
    throw InputError("--csv " + args.csv + ": write failed");
  }
  std::filesystem::rename(tmp, args.csv, ec);
  if (ec) throw InputError("--csv " + args.csv + ": " + ec.message());
  std::fprintf(stderr, "sim: %ld rows (%.3f s simulated, dt %.6g s) -> %s\n", rows, duration, scene.physics.dt,
               args.csv.c_str());
  reportTolerance(sim, scene);
  return 0;
}

// --poses: "t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz" (docs/EXPORT.md).
void writePoseRows(std::FILE* f, const PoseFrame& fr, const std::vector<std::string>& ids) {
  for (size_t i = 0; i < fr.bodies.size(); ++i) {
    const BodyPose& p = fr.bodies[i];
    std::fprintf(f, "%.9g,%zu,%s,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", fr.t,
                 i, ids[i].c_str(), p.x.x(), p.x.y(), p.x.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z(), p.v.x(), p.v.y(),
                 p.v.z(), p.w.x(), p.w.y(), p.w.z());
  }
}

int runPoses(const Scene& scene, double duration, const SimArgs& args) {
  // The times: --at as given (ascending, within the duration), --rate k/HZ, else every step.
  std::vector<double> times = args.at;
  for (size_t i = 0; i < times.size(); ++i) {
    if (!std::isfinite(times[i]) || times[i] < 0.0 || (i > 0 && times[i] < times[i - 1])) {
      throw InputError("--at: times must be ascending seconds >= 0");
    }
  }
  if (args.rate > 0.0) {
    const long n = static_cast<long>(std::floor(duration * args.rate + 1e-9)) + 1;
    for (long k = 0; k < n; ++k) times.push_back(double(k) / args.rate);
  }
  Sim sim(scene, &assimpAssets());
  sim.world().setStageTiming(false);  // as --csv
  // Written to a temporary name of this process and renamed (as --csv): a failed, stopped or
  // concurrent run never replaces a good file.
  const std::string tmp = args.poses + ".partial-" + std::to_string(getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) throw InputError("--poses " + args.poses + ": cannot write the file");
  std::fprintf(f, "t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n");
  const std::vector<std::string> ids = bodyIds(sim.world());
  PoseSampler sampler(sim);
  PoseFrame fr;
  long rows = 0;
  bool ok = true;
  int sig = 0;  // SIGINT or SIGTERM came: stop, write nothing
  if (times.empty()) {
    sampler.at(0.0, fr);
    writePoseRows(f, fr, ids);
    ++rows;
    const double end = duration - 0.5 * scene.physics.dt;
    while (ok && sim.time() < end && !(sig = InterruptGuard::signal())) {
      ok = sampler.nextStep(fr);
      if (ok) {
        writePoseRows(f, fr, ids);
        ++rows;
      }
    }
  } else {
    for (double t : times) {
      if ((sig = InterruptGuard::signal())) break;
      ok = sampler.at(t, fr);
      if (!ok) break;
      writePoseRows(f, fr, ids);
      ++rows;
    }
  }
  if (sig) {
    std::fclose(f);
    std::remove(tmp.c_str());
    std::fprintf(stderr, "ponyhop sim: stopped by %s; %s was not written\n", sig == SIGINT ? "SIGINT" : "SIGTERM",
                 args.poses.c_str());
    return InterruptGuard::exitCode(sig);
  }
  const bool written = std::fflush(f) == 0 && !std::ferror(f);
  std::fclose(f);
  if (!ok || !written) {
    std::remove(tmp.c_str());
    if (!ok) {
      std::fprintf(stderr, "ponyhop sim: the simulation stopped: %s\n  %s was not written\n", sim.status().c_str(),
                   args.poses.c_str());
      return 1;
    }
    throw InputError("--poses " + args.poses + ": write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, args.poses, ec);
  if (ec) throw InputError("--poses " + args.poses + ": " + ec.message());
  std::fprintf(stderr, "sim: %ld times x %zu bodies -> %s\n", rows, ids.size(), args.poses.c_str());
  reportTolerance(sim, scene);
  return 0;
}

int runSim(const SimArgs& args) {
  const Scene scene = args.scene.load();
  const double duration = args.duration >= 0.0 ? args.duration : scene.duration;
  if (!std::isfinite(duration) || duration > 1e6) {
    throw InputError("--duration: must be a number of seconds in [0, 1e6]");
  }
  if (args.csv.empty() && args.poses.empty()) throw InputError("nothing to write: give --csv FILE and/or --poses FILE");
  if (args.poses.empty() && (args.rate > 0.0 || !args.at.empty())) {
    throw InputError("--rate and --at choose the times of --poses rows: give --poses FILE");
  }
  if (args.rate > 0.0 && !args.at.empty()) throw InputError("--rate and --at: give one of them");
  if (!args.csv.empty()) checkOutputFile("--csv", args.csv, sceneInputs(scene));
  if (!args.poses.empty()) checkOutputFile("--poses", args.poses, sceneInputs(scene));
  InterruptGuard interrupt;
  if (!args.csv.empty()) {
    const int rc = runSummary(scene, duration, args);
    if (rc != 0) return rc;
  }
  return args.poses.empty() ? 0 : runPoses(scene, duration, args);
}

}  // namespace

void addSimCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<SimArgs>();
  auto* cmd = app.add_subcommand("sim", "Run the physics alone (no GL): a summary CSV and/or every body's pose");
  args->scene.add(cmd);
  cmd->add_option("--duration", args->duration, "Simulated seconds (default: the scene's duration)")
      ->check(finiteIn(0.0, 1e6));
  cmd->add_option("--csv", args->csv, "Summary CSV, one row per millisecond (tip or hopper state)")->check(nonEmpty());
  cmd->add_option("--poses", args->poses,
                  "Every body's pose and velocity as CSV: t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz")
      ->check(nonEmpty());
  cmd->add_option("--rate", args->rate, "--poses rows at t = k/RATE (interpolated between steps) instead of every step")
      ->check(finiteIn(1e-3, 1e6));
  cmd->add_option("--at", args->at, "--poses rows at these times (s, ascending, interpolated)")->delimiter(',');
  cmd->callback([args, &exit_code] { exit_code = runCommand("sim", [&] { return runSim(*args); }); });
}

}  // namespace ponyhop

// `ponyhop solve SCENE --out SOLVED.json [--knots K] [--iterations N] [--set key=value]...`: the
// goal solve (sim/goal_solve.h, docs/GOALS.md). Finds the least-effort guide torques that meet the
// scene's goals, prints each iteration, the goals' errors, the effort and the CPU time, says why
// a goal is not met, and writes the scene with its `guide` section (guide.enabled false replays
// the unguided motion). `--check`: no solve, the goals as the scene stands (its guide applied).
// `--spring`: no solve, the weakest goal spring that meets the goals (what film tools do), its
// stiffness and the energy it injects, for comparison (docs/GOALS.md); `--stiffness K` that
// spring instead, `--frames DIR` its motion drawn at the scene's frame rate (the springs are not a
// scene field, so `render` cannot replay them).
// Exit code 0 when every goal is met, 1 when one is not (the scene is still written: the closest
// control found), 2 for bad input.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "app/output_safety.h"
#include "app/scene_args.h"
#include "engine/asset_loader.h"
#include "engine/frame_writer.h"
#include "engine/render_session.h"
#include "sim/goal_solve.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

struct SolveArgs {
  SceneArgs scene;
  std::string out;
  bool check = false;
  bool spring = false;
  bool no_broyden = false;
  bool line_search = false;
  bool fixed_window = false;
  double stiffness = 0.0;  // --spring: this stiffness instead of the weakest that meets the goals
  std::string frames;      // --spring: the spring's motion drawn here
  GoalSolveOptions options;
};

void printReport(const Scene& scene, const GoalSolveReport& r) {
  for (const std::string& l : r.log) std::printf("%s\n", l.c_str());
  for (size_t g = 0; g < r.goals.size(); ++g) {
    const Goal& goal = scene.goals[g];
    const GoalOutcome& o = r.goals[g];
    std::printf("goal %zu: %s at t = %g s: error %.2f mm (tolerance %.2f mm), at (%.4f, %.4f, %.4f) m %s%s%s\n", g,
                goal.point.c_str(), goal.t, o.error * 1000.0, goal.tolerance * 1000.0, o.reached.x(), o.reached.y(),
                o.reached.z(), o.met ? "met" : "NOT MET", o.why.empty() ? "" : ": ", o.why.c_str());
  }
  const bool hopper_only =
      !scene.goals.empty() && std::all_of(scene.goals.begin(), scene.goals.end(),
                                          [](const Goal& g) { return g.point == "toe" || g.point == "body"; });
  if (!r.guide.script.empty() || hopper_only) {
    // The hopper's solved commands (sim/hopper_goal_solve.h): their effort against the scene's own.
    // The muscles' work beyond the scene's own course: measured by the solve (not by --check).
    char muscles[160] = "";
    if (r.energy != 0.0 || r.abs_energy != 0.0)
      std::snprintf(muscles, sizeof muscles,
                    ", the hopper's muscles %+.4g J of work (%+.4g J of integral of |power|) beyond its own course's",
                    r.energy, r.abs_energy);
    std::printf(
        "iterations %d, simulations %d, effort %.4g m^2/s (the commands against the scene's own)%s, CPU %.2f s\n",
        r.iterations, r.simulations, r.effort, muscles, r.cpu_seconds);
    return;
  }
  std::printf(
      "iterations %d, simulations %d, effort %.4g N^2 m^2 s, work %.4g J (integral of |power| %.4g J), CPU %.2f s\n",
      r.iterations, r.simulations, r.effort, r.energy, r.abs_energy, r.cpu_seconds);
}

// The spring's motion drawn at the scene's frame rate, frame_%05d.png in `dir` (the springs are
// not a scene field, so `render` cannot replay them).
void renderSpring(const Scene& scene_in, double stiffness, const std::string& dir) {
  Scene scene = scene_in;
  scene.guide.reset();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("--frames " + dir + ": " + ec.message());
  RenderSession session(scene);
  addGoalSprings(session.sim(), stiffness);
  FrameWriter writer(dir);
  std::string err;
  std::vector<uint8_t> rgba;
  for (int i = 0; i < scene.render.frames; ++i) {
    const double t = i / scene.render.fps;
    session.simulateTo(t);
    session.renderFrame(t, rgba);
    if (!writer.push(i, session.width(), session.height(), rgba, &err))
      throw InputError("--frames " + dir + ": " + err);
  }
  if (!writer.finish(&err)) throw InputError("--frames " + dir + ": " + err);
  std::fprintf(stderr, "solve: the spring's motion, %d frames -> %s\n", scene.render.frames, dir.c_str());
}

int runSolve(const SolveArgs& args) {
  Scene scene = args.scene.load();
  if (args.spring) {
    const SpringOutcome o = args.stiffness > 0.0 ? springGoals(scene, &assimpAssets(), args.stiffness)
                                                 : weakestGoalSpring(scene, &assimpAssets());
    if (!args.frames.empty()) renderSpring(scene, o.stiffness, args.frames);
    for (size_t g = 0; g < o.goals.size(); ++g)
      std::printf("goal %zu: %s at t = %g s: error %.2f mm %s\n", g, scene.goals[g].point.c_str(), scene.goals[g].t,
                  o.goals[g].error * 1000.0, o.goals[g].met ? "met" : "NOT MET");
    std::printf("goal spring: stiffness %.4g N/m, work %.4g J (integral of |power| %.4g J)%s\n", o.stiffness, o.work,
                o.abs_work, o.all_met ? "" : "; no stiffness up to 1e6 N/m meets every goal");
    return o.all_met ? 0 : 1;
  }
  if (args.check) {
    const GoalSolveReport r = evaluateGoals(scene, &assimpAssets());
    printReport(scene, r);
    return r.all_met ? 0 : 1;
  }
  if (args.out.empty()) throw InputError("--out: give the file the solved scene is written to (or --check)");
  checkOutputFile("--out", args.out, sceneInputs(scene));
  GoalSolveOptions options = args.options;
  options.broyden = !args.no_broyden;
  options.trust_region = !args.line_search;
  options.adaptive_window = !args.fixed_window;
  const GoalSolveReport r = solveGoals(scene, &assimpAssets(), options);
  printReport(scene, r);
  scene.guide = r.guide;
  saveScene(scene, args.out);
  std::fprintf(stderr, "solve: the scene with its guide -> %s (guide.enabled=false: the unguided motion)\n",
               args.out.c_str());
  return r.all_met ? 0 : 1;
}

}  // namespace

void addSolveCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<SolveArgs>();
  auto* cmd = app.add_subcommand(
      "solve", "Find the gentlest joint torques that meet the scene's goals and write them into the scene (its guide)");
  args->scene.add(cmd);
  cmd->add_option("--out", args->out, "The solved scene (JSON)")->check(nonEmpty());
  cmd->add_flag("--check", args->check, "Solve nothing: the goals' errors as the scene stands (its guide applied)");
  cmd->add_flag("--spring", args->spring,
                "Solve nothing: the weakest goal spring that meets the goals, and the energy it injects");
  cmd->add_option("--knots", args->options.knots,
                  "Knot times per joint over [0, last goal time] (0: four knot intervals per window)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--window", args->options.window,
                  "Seconds before each goal whose torques meet it, the earlier goals' frozen (0: all goals at once)")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--joints", args->options.joints, "Guide only the root-most N joints (0: every joint)")
      ->check(CLI::Range(0, 4096));
  cmd->add_option("--stiffness", args->stiffness, "With --spring: this stiffness (N/m) instead of the weakest")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--frames", args->frames, "With --spring: draw the spring's motion into this folder")
      ->check(nonEmpty());
  cmd->add_flag("--no-broyden", args->no_broyden, "Differences for the Jacobian at every iteration (no updates)");
  cmd->add_flag("--fixed-window", args->fixed_window,
                "A window that does not meet its goal stays as it is (no doubling toward the previous goal)");
  cmd->add_flag("--line-search", args->line_search,
                "Full Gauss-Newton steps halved until the error falls, instead of the trust region");
  cmd->add_option("--fd-step", args->options.fd_step, "Forward-difference step of a knot torque, N m")
      ->check(CLI::Range(1e-12, 1.0));
  cmd->add_option("--damping", args->options.initial_damping,
                  "The trust region's first damping, in units of the mean of diag(J G^-1 J^T)")
      ->check(CLI::Range(0.0, 1e12));
  cmd->add_option("--iterations", args->options.max_iterations,
                  "Most iterations per window (a trust-region iteration is one trial run)")
      ->check(CLI::Range(1, 1000));
  cmd->callback([args, &exit_code] { exit_code = runCommand("solve", [&] { return runSolve(*args); }); });
}

}  // namespace ponyhop

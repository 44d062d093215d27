// The goal solve (docs/GOALS.md): spacetime constraints (Witkin & Kass 1988) by shooting, the goals
// met in time order over short windows before each (sequential shooting) or all at once (single).
// The unknowns are the chain's guide torques (physics/models/guide.h) at K knot times per joint,
// uniform over [0, T] (T: the last goal's time; one more knot, fixed at zero, ends the curve a
// knot interval later). The solve minimizes the effort E = integral of sum_j |tau_j(t)|^2 dt, a
// quadratic form c^T G c of the knot torques c, subject to the goals r_g(c) = x_g(c) - p_g = 0,
// by Gauss-Newton SQP: each iteration takes the goals' Jacobian J by forward differences (each
// column a run from the last snapshot before the knot's support starts) and steps to the least
// effort that meets the linearized goals, with a backtracking line search on the goal error.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "sim/assets.h"
#include "sim/scene.h"

namespace ponyhop {

class Sim;

struct GoalSolveOptions {
  // Knot times per joint over [0, T]; 0: four knot intervals per window (6 knots with no windows).
  int knots = 0;
  // s: each goal is met in time order by the torques within this long a time before it, the
  // earlier ones frozen (sequential shooting, docs/GOALS.md); 0: every knot for every goal at once
  // (single shooting).
  double window = 0.75;
  // A goal its window did not meet is tried again with a window twice as long (up to the
  // previous goal), keeping what the shorter one reached.
  bool adaptive_window = true;
  int max_iterations = 30;  // iterations per window (a trust-region iteration is one trial run)
  // N m, the forward-difference step of a knot torque component: large enough that the jumps of
  // the step decisions (a substep split, a contact made a step earlier) are small beside the
  // change it makes, a few per cent of the torques a goal needs (docs/GOALS.md).
  double fd_step = 1e-4;
  // Levenberg-Marquardt per window (docs/GOALS.md): each iteration one trial step, damped by how
  // well the linearization predicted the last; false: the Gauss-Newton step with backtracking.
  bool trust_region = true;
  double initial_damping = 1.0;  // the first damping, in units of the mean of diag(J G^-1 J^T)
  // Line search: a step that does not lower the goal error is halved this often, then the solve stops.
  int max_line_halvings = 5;
  // After the first Jacobian by differences, Broyden's rank-one updates along the steps taken
  // (differences again when an updated one gives no step); false: differences every iteration.
  bool broyden = true;
  int joints = 0;  // the guided joints: the root-most `joints` (0: every joint)
};

// How one goal came out.
struct GoalOutcome {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();   // m, world, at the goal's time
  Eigen::Vector3d reached = Eigen::Vector3d::Zero();  // m, world, where the point was
  double error = 0.0;                                 // m, |reached - target|
  bool met = false;                                   // error <= the goal's tolerance
  std::string why;                                    // not met: what stopped it ("" when met)
};

struct GoalSolveReport {
  std::vector<GoalOutcome> goals;  // in the scene's order
  GuideParams guide;               // the solved torques (the scene's `guide` section)
  int iterations = 0;
  int simulations = 0;       // runs, whole or partial (a Jacobian column is a partial one)
  double effort = 0.0;       // N^2 m^2 s, integral of sum_j |tau_j|^2
  double energy = 0.0;       // J, net work of the torques on the chain up to the last goal
  double abs_energy = 0.0;   // J, integral of |power| over the same time
  double cpu_seconds = 0.0;  // process CPU time of the solve
  bool all_met = false;
  std::vector<std::string> log;  // one line per iteration: goal errors, effort, line search
};

// Solves for the guide that meets `scene`'s goals with the least effort. The scene's own guide is
// ignored (the solve starts from zero torque). Throws InputError when the scene has no goals or
// no chain to guide.
GoalSolveReport solveGoals(const Scene& scene, const AssetLoader* assets, const GoalSolveOptions& options = {});

// The goals as the scene stands (its guide, if any and enabled, applied): where each point was at
// its time, and the guide's effort and injected energy (report.guide is the scene's).
GoalSolveReport evaluateGoals(const Scene& scene, const AssetLoader* assets);

// What film tools do instead (a goal spring, Maya's goal attract, Houdini's pin to animation), for
// comparison: each goal's point is pulled toward its target by a spring of stiffness k (N/m) from
// the previous goal's time (or 0) to its own, then let go. One run at k.
struct SpringOutcome {
  double stiffness = 0.0;          // N/m
  std::vector<GoalOutcome> goals;  // in the scene's order
  double work = 0.0;               // J, net work of the springs on the chain
  double abs_work = 0.0;           // J, integral of |power|
  bool all_met = false;
};
SpringOutcome springGoals(const Scene& scene, const AssetLoader* assets, double stiffness);
// Adds the goal springs of stiffness k (N/m) to `sim` (built from a scene with goals and without
// its guide), as springGoals runs them: for drawing the spring's motion.
void addGoalSprings(Sim& sim, double stiffness);
// The least stiffness (to 2 %) at which the springs meet every goal, searched by doubling from
// 1e-3 N/m and bisecting in log; all_met false when 1e6 N/m does not.
SpringOutcome weakestGoalSpring(const Scene& scene, const AssetLoader* assets);

// The Jacobian of the goals' points (rows 3g..3g+2: goal g, world, m) in the knot torques c (the
// solve's unknowns for `knots` knots per joint: c[(j K + k) 3 + d], N m), by forward or central
// differences of `step`: what the solve uses, for the gradient check (docs/GOALS.md).
Eigen::MatrixXd goalJacobian(const Scene& scene, const AssetLoader* assets, int knots, const Eigen::VectorXd& c,
                             double step, bool central);

}  // namespace ponyhop

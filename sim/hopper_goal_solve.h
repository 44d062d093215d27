// The hopper's goal solve (docs/GOALS.md, "The hopper"): the first hopper's toe or body centre at a
// place at a time, met by its Raibert controller's own commands over time, so that the result is
// still the controller hopping. The unknowns are the commanded velocity (vx, vy) and apex height at
// K keys, uniform over [0, T] (T: the last goal's time), each in force from its time on, like the
// scene's hopper.script; one more key at T gives the scene's own command back. The solve looks for
// the commands closest to the scene's own (the effort below) that meet the goals, by shooting with
// Levenberg-Marquardt on the goal error plus a small multiple of the effort, the Jacobian by forward
// differences from the snapshot at each key (a key changes nothing before its time).
#pragma once

#include <vector>

#include "physics/models/hopper_params.h"
#include "sim/goal_solve.h"

namespace ponyhop {

struct HopperGoalSolveOptions {
  int keys = 0;  // command keys over [0, T]; 0: one per 0.5 s (at least 2)
  int max_iterations = 30;
  double fd_speed = 0.02;   // m/s, the forward-difference step of a velocity command
  double fd_height = 0.01;  // m, of an apex-height command
};

// Solves for the first hopper's commands that meet `scene`'s goals, every one of them a hopper
// point (toe, body): report.guide.script (the scene's guide knots are kept); report.energy and
// abs_energy: the hopper's muscles' work beyond the scene's own course up to the last goal (J).
// Throws InputError when the scene has no hopper, no goals, or a goal on the chain.
GoalSolveReport solveHopperGoals(const Scene& scene, const AssetLoader* assets,
                                 const HopperGoalSolveOptions& options = {});

// The effort of a course against the scene's own commands: the integral over [0, until] of
// |v_cmd - v_scene|^2 + (h_cmd - h_scene)^2 / (1 s)^2 (m^2/s), zero for the scene's own course.
double hopperCommandEffort(const Scene& scene, const std::vector<HopperCommandKey>& script, double until);

}  // namespace ponyhop

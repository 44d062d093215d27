// The knobs that trade speed for accuracy: time step, substeps, integrator, solver,
// stabilization. Plain data with defaults and units; the step's state lives in World.
#pragma once

#include <Eigen/Core>

#include "physics/reflect.h"

namespace ponyhop {

// docs/STABILITY.md: what each is for, the default and why, measured stability limits.
enum class Integrator { SymplecticEuler, RK4, Rattle, ImplicitEuler };
template <>
struct EnumNames<Integrator> {
  static constexpr std::array<std::string_view, 4> names{"symplectic_euler", "rk4", "rattle", "implicit_euler"};
};

// docs/SOLVERS.md: dense (J M^-1 J^T, LDLT, O(m^3)), tree (Baraff's block LDL^T of the augmented
// system in tree order, O(n)), featherstone (reduced coordinates, articulated-body algorithm, O(n)).
enum class SolverKind { Dense, Tree, Featherstone };
template <>
struct EnumNames<SolverKind> {
  static constexpr std::array<std::string_view, 3> names{"dense", "tree", "featherstone"};
};

// velocity: symplectic Euler's joints at velocity level, as game engines (ODE, Box2D, Bullet)
// hold them: each step's multipliers make J v' = -erp C / h instead of J a = -J' v (docs/PHYSICS.md).
enum class Stabilization { None, Baumgarte, Projection, Velocity };
template <>
struct EnumNames<Stabilization> {
  static constexpr std::array<std::string_view, 4> names{"none", "baumgarte", "projection", "velocity"};
};

struct PhysicsParams {
  double dt = 1.0 / 240.0;  // s, one physics step (independent of the frame rate)
  int substeps = 1;         // steps per dt at least (the step actually taken is dt / substeps or smaller)
  // RATTLE (constrained Stormer-Verlet, symplectic): positions and velocities on the joints
  // every step, bounded energy error; with max_step_rotation it holds the whipping chain at any
  // dt from 1/60 to 1/1920 s (docs/STABILITY.md).
  Integrator integrator = Integrator::Rattle;
  // tree: the same multipliers as dense (the same equations, any joint graph) in O(n); at 8
  // links already half dense's cost per RATTLE step (docs/SOLVERS.md).
  SolverKind solver = SolverKind::Tree;
  Stabilization stabilization = Stabilization::Projection;
  // Baumgarte: C'' + 2 alpha C' + beta^2 C = 0 (alpha in 1/s, beta in 1/s).
  double baumgarte_alpha = 10.0;  // 1/s
  double baumgarte_beta = 10.0;   // 1/s
  // stabilization = velocity: the share of the joints' position error a step corrects (ODE's
  // error reduction parameter).
  double erp = 0.2;
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  // m/s^2, world frame (z up)
  // Automatic substeps: each dt starts with enough substeps that the fastest body turns at most
  // this much per substep. RATTLE: at the end of the dt too, else the dt is taken again with the
  // end's count; the other methods: a step in which a body turns more than 1.25x this is split
  // in two (docs/STABILITY.md). 0 = off (exactly `substeps` per dt).
  double max_step_rotation = 2.0;  // deg per substep (2: energy within 1 % through the whip)
  // Accuracy instead of a step size: > 0 chooses the substeps of every dt by step doubling so
  // that the estimated position errors of the substeps of one simulated second add up to at
  // most this (each substep of h may add tolerance h / 1 s; World::lastSubsteps(),
  // lastErrorEstimate(), errorEstimateSum()). 0 = off (then max_step_rotation applies).
  double tolerance = 0.0;  // m
  // Adaptive dynamics (docs/SOLVERS.md; solver featherstone): each step only the joints that
  // matter move, the rest are held rigid. adaptive_joints: at most this many joints move (0 = no
  // cap); adaptive_tolerance: a joint moves when its score (kinetic energy of its relative motion
  // plus h^2 times that of its acceleration) is above it (J; 0 = off). Both 0: off.
  int adaptive_joints = 0;
  double adaptive_tolerance = 0.0;  // J

  template <class V>
  void reflect(V& v) {
    v("dt", dt, {.unit = "s", .min = 1e-6, .max = 0.1, .help = "Physics time step", .log = true});
    v("substeps", substeps,
      {.min = 1, .max = 1000, .help = "Steps taken per dt", .log = true, .soft_min = 1, .soft_max = 64});
    v("integrator", integrator, {.help = "Time integration method"});
    v("solver", solver, {.help = "How constraint forces are solved"});
    v("stabilization", stabilization,
      {.help = "Correction of joint drift (velocity: symplectic Euler's joints at velocity level, as game engines)"});
    v("baumgarte_alpha", baumgarte_alpha,
      {.unit = "1/s", .min = 0, .max = 1e4, .help = "Baumgarte velocity gain (C'' + 2aC' + b^2C = 0)"});
    v("baumgarte_beta", baumgarte_beta,
      {.unit = "1/s", .min = 0, .max = 1e4, .help = "Baumgarte position gain (C'' + 2aC' + b^2C = 0)"});
    v("erp", erp,
      {.min = 0,
       .max = 1,
       .help = "stabilization = velocity: share of the joint error corrected per step (ODE's ERP)"});
    v("gravity", gravity, {.unit = "m/s^2", .min = -1000, .max = 1000, .help = "Gravity, world frame (z up)"});
    v("max_step_rotation", max_step_rotation,
      {.unit = "deg", .min = 0, .max = 180, .help = "Largest turn of a body per substep; sets the substeps (0 = off)"});
    v("tolerance", tolerance,
      {.unit = "m", .min = 0, .max = 1, .help = "Position error per simulated second; picks the substeps (0 = off)"});
    v("adaptive_joints", adaptive_joints,
      {.min = 0,
       .max = 1000000,
       .help = "Adaptive dynamics: at most this many joints move per step, the rest rigid (0 = off)",
       .soft_max = 256});
    v("adaptive_tolerance", adaptive_tolerance,
      {.unit = "J",
       .min = 0,
       .max = 1e6,
       .help = "Adaptive dynamics: a joint moves when its motion score is above this (0 = off)",
       .log = true,
       .soft_min = 1e-12,
       .soft_max = 1});
  }
};

}  // namespace ponyhop

// The simulated world: bodies, joints and force elements, and the step that advances them
// (Hecker lecture, "Simulation Loop - Control"). Parameters come in PhysicsParams; the state
// (bodies, time, status) lives here. Physics never prints: when a step goes wrong, the world
// stops and status() says when, in which stage, and the likely cause.
#pragma once

#include <any>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "physics/constraint.h"
#include "physics/constraint_solver.h"
#include "physics/controller.h"
#include "physics/featherstone.h"
#include "physics/force_elements.h"
#include "physics/integrator.h"
#include "physics/physics_params.h"
#include "physics/rattle.h"
#include "physics/rigid_body.h"
#include "physics/rk4.h"
#include "physics/stability_monitor.h"
#include "physics/stabilization.h"
#include "physics/stage_times.h"
#include "physics/status.h"

namespace ponyhop {

class World {
 public:
  explicit World(const PhysicsParams& params);  // bad params: !ok(), status() says why
  // Defined where the integrator schemes are complete (world.cpp); a World moves (Sim keeps one
  // by value) and is not copied.
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  // Building. Each returns the new index.
  int addDynamicBody(RigidBody body);
  int addKinematicBody(KinematicMotion motion, std::string name);  // state set at time()
  int addJoint(std::unique_ptr<Constraint> joint);
  int addForceElement(std::unique_ptr<ForceElement> element);
  // Controllers (think + controller forces) and contact sets (the contact stage), any number,
  // called in the order added (physics/controller.h).
  void addController(std::shared_ptr<Controller> controller);
  void addContactSet(std::shared_ptr<ContactSet> contacts);
  // Potential energy reported = gravity + springs - reference (builders set the zero).
  void addPotentialReference(double joules) { potential_reference_ += joules; }
  // Stops the world with a message (builders: invalid parameters).
  void fail(std::string message);

  // Advance by params().dt in params().substeps equal steps or more (max_step_rotation,
  // tolerance: docs/STABILITY.md). Does nothing once !ok().
  void step();
  // Substeps the last step() took (after automatic splitting / error control), and the largest
  // estimated position error of one of them (m; tolerance mode only, else 0).
  int lastSubsteps() const { return last_substeps_; }
  double lastErrorEstimate() const { return last_error_; }
  // Tolerance mode: substeps accepted since the start whose estimate was still above their
  // budget (tolerance h / 1 s) at the deepest split (the promise not kept; 0 when it always was).
  int toleranceMisses() const { return tolerance_misses_; }
  // Tolerance mode: the sum of the accepted substeps' error estimates since the start (m), the
  // global position error to first order (no growth or cancellation between substeps).
  double errorEstimateSum() const { return error_sum_; }
  // The order of the method in use (1 symplectic/implicit Euler, 2 RATTLE, 4 RK4).
  int methodOrder() const;
  // RATTLE: the position solve's iterations summed over every step taken since construction
  // (steps later undone by a split included): what its warm start saves.
  long rattleIterations() const { return rattle_iterations_; }
  // RATTLE's corrector for velocity-dependent forces (physics/rattle.h; on by default, and only
  // run when a force element or controller dependsOnVelocity()). Off: the classical explicit
  // second kick, first order with damping: for tests that measure what the corrector buys.
  void setRattleCorrector(bool on) { rattle_corrector_ = on; }

  // The force stages at the current state and time, without stepping: fills every dynamic
  // body's a, alpha and constraint force/torque, and lambda(). For tests and drawing forces.
  // RATTLE steps do not run the acceleration-level solve (docs/STABILITY.md, "RATTLE's warm
  // start"): after one, the bodies' a, alpha and constraint force/torque are RATTLE's own at the
  // end of the step (physics/rattle.h), and lambda() is brought up to date on demand.
  void evaluate();
  // Velocities of the dynamic bodies onto the joints' velocity constraints (J v = -J_k v_k) in
  // the mass metric: the least-kinetic-energy consistent velocities (Kelvin). Stops the world
  // when it fails.
  void projectVelocities();
  // The projections of physics/stabilization.h through this world's solver (dense, tree, ...),
  // at the bodies' current state, for contact sets (impacts). They do not stop the world:
  // ok or what failed. `impulses`: the velocity projection's multiplier of every row (N s).
  ProjectionResult projectPositionsOntoJoints();
  // Assembly at build time (a scene's loops): the bodies walked onto C = 0 by damped steps of at
  // most 1 cm (projectPositions with a max_step), up to 1000 of them, then Newton to 1e-12.
  ProjectionResult assembleJoints();
  Status projectVelocitiesOntoJoints(Eigen::VectorXd* impulses = nullptr);

  // RATTLE's warm start: the position multipliers of the last step taken and the joints'
  // dimensions (rows) they belong to; valid once a RATTLE step succeeded.
  struct WarmStart {
    Eigen::VectorXd mu;
    std::vector<int> dims;
    bool valid = false;
  };

  // What a step carries to the next besides the bodies' and the controllers' and contact sets'
  // own state: the time, the step control's and the integrator's memory, the status. World keeps
  // it as one member (state_), so a snapshot is one assignment.
  struct StepState {
    double time = 0.0;
    StabilityMonitor monitor;
    WarmStart warm_start;
    int tolerance_substeps = 0;  // tolerance mode: substeps to start the next dt with
    std::string status;          // "" while running; a restore of a running state revives a stopped world
  };

  // A complete snapshot: every body's state, the controllers' and contact sets' own state and
  // the world's; restoreState(saveState()) continues bit for bit as before.
  struct SavedState {
    std::vector<BodyState> bodies;
    std::vector<std::any> controllers;
    std::vector<std::any> contacts;
    StepState step;
  };
  SavedState saveState() const;
  // The same into storage `s` already has (step() keeps one per world: no allocation per dt
  // for the bodies once sized).
  void saveStateInto(SavedState& s) const;
  void restoreState(const SavedState& s);

  double time() const { return state_.time; }
  const PhysicsParams& params() const { return params_; }
  bool ok() const { return state_.status.empty(); }
  const std::string& status() const { return state_.status; }

  int bodyCount() const { return static_cast<int>(bodies_.size()); }
  RigidBody& body(int i) { return bodies_[i]; }
  const RigidBody& body(int i) const { return bodies_[i]; }
  const std::vector<RigidBody>& bodies() const { return bodies_; }
  std::vector<RigidBody>& bodies() { return bodies_; }
  const Constraints& joints() const { return joints_; }
  const ConstraintSolver& solver() const { return *solver_; }
  // The solver as the last stabilize() left it (J M^-1 J^T factored at the bodies' poses after the
  // position projection), when nothing has factored it since and every body is still where it was
  // then, bit for bit; else null. The contact stage runs right after the stabilize of its substep
  // and solves with it instead of factoring the same matrix again (Collisions::buildDelassus).
  const ConstraintSolver* solverFactoredAt(const std::vector<RigidBody>& bodies) const;
  // The reduced-coordinate system (physics.solver = featherstone), else null.
  const ArticulatedSystem* reduced() const { return reduced_.get(); }
  ArticulatedSystem* reduced() { return reduced_.get(); }
  // The multipliers of the acceleration-level joint-force solve (one per constraint row). After
  // a RATTLE step, which does not run that solve, the non-const overload runs it first
  // (evaluate(): at the current state, so the values are exact, not RATTLE's); the const one
  // returns the last solve's, which may then be from an earlier state (call evaluate() first).
  const Eigen::VectorXd& lambda();
  const Eigen::VectorXd& lambda() const { return solver_->lambda(); }

  // Time per stage of step() since construction or the last reset (physics/stage_times.h): wall
  // time, or the thread's CPU time after setStageClock(StageClock::Source::ThreadCpu).
  const StageTimes& stageTimes() const { return clock_.times(); }
  void resetStageTimes() { clock_.reset(); }
  // Off: the stages are not timed (no clock reads; stageTimes() keeps its seconds and still
  // counts calls). On by default. Call between steps.
  void setStageTiming(bool on) { clock_.setEnabled(on); }
  // The stage clock's source and the stages it times (StageClock::bit(stage) or'ed).
  void setStageClock(StageClock::Source s, unsigned stages = StageClock::kAllStages) { clock_.setSource(s, stages); }

  double kineticEnergy() const;    // J, dynamic bodies
  double potentialEnergy() const;  // J, gravity + springs - reference
  double energy() const { return kineticEnergy() + potentialEnergy(); }
  double maxJointError() const;  // max |C| over joints at the current state (m)
  // Power of the constraint forces on the dynamic bodies at the last evaluation, W:
  // sum F_c . v + t_c . w (zero for workless joints with fixed kinematic parents).
  double constraintPower() const;

 private:
  // The integrators behind one interface (physics/integrator_scheme.h), chosen once from
  // params.integrator: each owns its stages of a substep and says what step control it needs.
  class IntegratorScheme;
  class ForceStagesScheme;
  class SymplecticEulerScheme;
  class Rk4Scheme;
  class RattleScheme;
  class ImplicitEulerScheme;
  static std::unique_ptr<IntegratorScheme> makeIntegratorScheme(Integrator kind);

  // The stages of a step, in the method's order.
  void think();
  void updateKinematicBodies(double t);
  void applyExternalForces();
  void applyControllerForces();
  void solveJointForces();
  void integrate(double h);
  void stabilize();
  // Symplectic Euler with projection: its position solve (shakePositions) may fail and split the substep.
  bool shakes() const;
  void resolveContacts();
  bool impactInside() const;   // any contact set's impact within the substep just taken
  void reducedStep(double h);  // featherstone: replaces joint forces + integrate + stabilize
  // What a constrained integrator (RATTLE, implicit Euler) is lent for one step, and the end of
  // such a step: false when it failed (split_reason_ set) or the world stopped; else t += h and
  // the bodies checked.
  ConstrainedStep constrainedStep();
  bool finishConstrainedStep(const ConstrainedStepResult& r, double h);

  void substep(double h, int depth = 0);
  void advanceToTolerance(double h, int depth);
  // The substep count holds at both ends of each dt (RATTLE, not featherstone), and no substep
  // is split for its turn (World::step, takeStep).
  bool symmetricCount() const;
  bool takeStep(double h);  // stages 1-6 of one substep; false: split it (or stopped)
  void watchStability(double h);
  void followTeleports(double h);
  double maxAngularSpeed() const;
  bool warmStartFits() const;            // state_.warm_start belongs to the current joint rows
  bool velocityDependentForces() const;  // any force element or controller reads velocities
  // A substep's start: the dynamic bodies' states and the world's (a rejected step's warm start
  // must not seed the retry).
  struct Snapshot {
    State bodies;
    StepState step;
  };
  Snapshot snapshot() const { return {gatherState(), state_}; }
  // The same into `s`, reusing its storage (substep(): a steady step allocates nothing).
  void snapshotInto(Snapshot& s) const;
  void restore(const Snapshot& s);
  double errorDistance(const State& a, const State& b) const;  // advanceToTolerance()'s norm (m)
  void accelerationsAt(double t, const State& state, Accelerations& out);
  State gatherState() const;
  void scatterState(const State& state);
  // The same into existing storage (a steady step allocates nothing).
  void gatherStateInto(State& out) const;
  void gatherAccelerationsInto(Accelerations& out) const;
  bool checkBodies(const char* stage, bool accelerations);
  bool checkForces(const RigidBody& b);  // applyExternalForces: stops the world when b's state or forces are not finite
  void stop(const char* stage, const std::string& what, const char* cause);

  // Parameters.
  PhysicsParams params_;
  bool rattle_corrector_ = true;

  // The model: bodies (their state included: RigidBody::state()), joints, forces, controllers,
  // contact sets, and the methods that move them.
  std::vector<RigidBody> bodies_;
  std::vector<int> dynamic_;  // indices of the dynamic bodies, in state order
  Constraints joints_;
  ForceElements forces_;
  std::vector<std::shared_ptr<Controller>> controllers_;
  std::vector<std::shared_ptr<ContactSet>> contacts_;
  double potential_reference_ = 0.0;
  std::unique_ptr<ConstraintSolver> solver_;
  std::unique_ptr<ArticulatedSystem> reduced_;  // featherstone only
  std::unique_ptr<IntegratorScheme> scheme_;

  // The state (besides the bodies'): what saveState() keeps.
  StepState state_;

  // Scratch: work space and what one step tells the next stage (a steady step allocates nothing).
  ConstraintSystem system_;
  double stage_time_ = 0.0;               // time of the force evaluation in progress (RK4 stages)
  std::string split_reason_;              // set by a stage that wants the substep split ("" = fine)
  std::vector<Snapshot> substep_starts_;  // substep()'s snapshot per split depth
  SavedState dt_start_;                   // step(): the dt's start, for RATTLE's redo at the end's count
  RattleWork rattle_work_;                // RATTLE: the step's work space (sized once)
  // stabilize(): the solver's generation after the velocity projection's factorization and the
  // poses it was factored at (solverFactoredAt()); 0: none.
  unsigned long stabilized_generation_ = 0;
  std::vector<Eigen::Vector3d> stabilized_x_;
  std::vector<Eigen::Quaterniond> stabilized_q_;
  ProjectionWork projection_work_;  // stabilize(): the projections' work space (sized once)
  ShakeWork shake_work_;            // stabilize() after symplectic Euler: its start and J(q_n)
  Rk4Work rk4_work_;                // RK4 (multiplier solvers): the stages (sized once)
  // The bodies moved since the last acceleration-level solve (a RATTLE step, a restore):
  // lambda() runs it on demand.
  bool forces_stale_ = false;
  State state_scratch_;  // watchStability() and integrate()
  Accelerations acc_scratch_;
  bool gathered_ = false;    // watchStability() filled the scratch just before integrate()
  double force_step_ = 0.0;  // s, the substep the force stages ran for (stabilization = velocity)

  // Diagnostics.
  StageClock clock_;  // per-stage timing (stageTimes())
  int last_substeps_ = 0;
  double last_error_ = 0.0;
  int tolerance_misses_ = 0;       // substeps accepted above their budget at the deepest split
  long rattle_iterations_ = 0;     // rattleIterations()
  double last_error_ratio_ = 0.0;  // step(): the largest estimate / budget of the dt (tolerance mode)
  double error_sum_ = 0.0;         // errorEstimateSum()
};

}  // namespace ponyhop

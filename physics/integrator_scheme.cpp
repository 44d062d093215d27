#include "physics/integrator_scheme.h"

#include <memory>

#include "physics/implicit_euler.h"
#include "physics/rattle.h"
#include "physics/rk4.h"
#include "physics/symplectic_euler.h"

namespace ponyhop {

using checks::finite;
using checks::finiteAndBounded;

// The methods that start a substep from the full force stages at t (kinematic bodies, external
// and controller forces, the joint-force solve) and integrate from their accelerations:
// symplectic Euler, RK4 (which re-runs those stages at its stage times) and linearly implicit
// Euler (which re-evaluates the forces itself).
class World::ForceStagesScheme : public World::IntegratorScheme {
 public:
  void takeStep(World& w, double h) override {
    w.force_step_ = h;                       // the step the joint-force stage is for (stabilization = velocity)
    w.updateKinematicBodies(w.state_.time);  // prescribed bodies: pose, velocity, acceleration at t
    w.followTeleports(h);                    // a prescribed body that jumps within the step carries its chain along
    w.applyExternalForces();                 // gravity, joint damping, bending springs, air drag
    w.applyControllerForces();               // controllers' force laws (none for chains; the hopper's muscles)
    w.solveJointForces();                    // A lambda = b, F_c = J^T lambda, body accelerations
    w.watchStability(h);                     // explicit methods: stop when h is beyond the stability limit
    w.integrate(h);                          // t += h (RK4 re-runs the four stages above at its stage times)
    w.stabilize();                           // projection onto C = 0 and J v = -J_k v_k (when chosen)
  }
};

class World::SymplecticEulerScheme final : public World::ForceStagesScheme {
 public:
  Integrator kind() const override { return Integrator::SymplecticEuler; }
  int order() const override { return 1; }
  bool mayFail() const override { return false; }
  double stabilityLimit() const override { return 2.0; }
  bool observesInPlace() const override { return true; }

  void integrate(World& w, double h, bool /*gathered*/) override {
    // In place on the bodies from their accelerations (the joint-force stage's; nothing moved
    // them since), and checked in the same pass (checkBodies only to say which body and stop).
    // Its quaternions are unit (normalized by the step). The same operations as stepping a
    // gathered copy and copying it back.
    bool fine = true;
    // With projection the stabilize stage needs the step's start and J(q_n) (shakePositions,
    // physics/stabilization.h): the joint-force stage evaluated the system there and left A(q_n)
    // factored.
    const bool shake = w.shakes();
    if (shake) {
      w.shake_work_.jn = w.system_;  // same rows as last step: copied into the storage it has
      w.shake_work_.held_generation = w.solver_->generation();
      w.shake_work_.h = h;
      w.shake_work_.start.resize(w.bodies_.size());
    }
    for (int i : w.dynamic_) {
      RigidBody& b = w.bodies_[i];
      if (shake) {
        ShakeStart& s = w.shake_work_.start[size_t(i)];
        s.x = b.x;
        s.q = b.q;
      }
      symplecticEulerStep(h, b.a, b.alpha, b.state());
      if (shake) {
        ShakeStart& s = w.shake_work_.start[size_t(i)];
        s.v = b.v;
        s.w = b.w;
      }
      fine = fine && finiteAndBounded(b.x) && finite(b.q.coeffs()) && finiteAndBounded(b.v) && finiteAndBounded(b.w);
    }
    w.state_.time += h;
    w.stage_time_ = w.state_.time;
    if (!fine) w.checkBodies("integrate", false);
  }
};

class World::Rk4Scheme final : public World::ForceStagesScheme {
 public:
  Integrator kind() const override { return Integrator::RK4; }
  int order() const override { return 4; }
  bool mayFail() const override { return false; }
  double stabilityLimit() const override { return 2.83; }

  void integrate(World& w, double h, bool gathered) override {
    State& state = w.state_scratch_;
    if (!gathered) {
      w.gatherStateInto(state);
      w.gatherAccelerationsInto(w.acc_scratch_);
    }
    rk4Step(
        w.state_.time, h, w.acc_scratch_,
        [&w](double t, const State& s, Accelerations& out) { w.accelerationsAt(t, s, out); }, state, w.rk4_work_);
    if (!w.ok()) return;  // a stage evaluation stopped the world
    w.state_.time += h;
    w.stage_time_ = w.state_.time;
    w.scatterState(state);
    w.checkBodies("integrate", false);
  }
};

class World::ImplicitEulerScheme final : public World::ForceStagesScheme {
 public:
  Integrator kind() const override { return Integrator::ImplicitEuler; }
  int order() const override { return 1; }
  bool mayFail() const override { return true; }
  double stabilityLimit() const override { return 0.0; }

  void integrate(World& w, double h, bool /*gathered*/) override {
    ConstrainedStep cs = w.constrainedStep();
    w.finishConstrainedStep(linearlyImplicitEulerStep(w.state_.time, h, cs), h);
  }
};

// RATTLE evaluates the forces at t itself (its first kick) and needs no acceleration-level
// solve: its position multipliers start from the last step's (warm start). Only when there are
// none for these rows (first step, a contact added or dropped rows, a restored state from before
// any step) the joint-force solve at t seeds them. It keeps positions and velocities on the
// joints by construction: no stabilize stage.
class World::RattleScheme final : public World::IntegratorScheme {
 public:
  Integrator kind() const override { return Integrator::Rattle; }
  int order() const override { return 2; }
  bool mayFail() const override { return true; }
  double stabilityLimit() const override { return 2.0; }
  bool symmetricCount() const override { return true; }

  void takeStep(World& w, double h) override {
    w.updateKinematicBodies(w.state_.time);  // prescribed bodies: pose, velocity, acceleration at t
    w.followTeleports(h);                    // a prescribed body that jumps within the step carries its chain along
    if (!w.warmStartFits()) {
      w.applyExternalForces();
      w.applyControllerForces();
      w.solveJointForces();
      if (w.ok()) w.state_.warm_start.mu = w.solver_->lambda();
    }
    w.integrate(h);  // t += h: kick, drift, position solve, kick, velocity solve
    // After the step: its end state with its end accelerations (the second kick's, which a step
    // that is later undone takes back with the monitor's snapshot).
    if (w.split_reason_.empty()) w.watchStability(h);
  }

  void integrate(World& w, double h, bool /*gathered*/) override {
    ConstrainedStep cs = w.constrainedStep();
    RattleOptions options;
    options.correct_velocity_forces = w.rattle_corrector_ && w.velocityDependentForces();
    options.work = &w.rattle_work_;
    // mu: the guess in, this step's out.
    const ConstrainedStepResult r = rattleStep(w.state_.time, h, w.state_.warm_start.mu, cs, options);
    w.rattle_iterations_ += r.iterations;
    if (!w.finishConstrainedStep(r, h)) return;
    // The next step's guess. Sized once per row layout: a steady step allocates nothing here.
    WarmStart& warm = w.state_.warm_start;
    warm.dims.resize(w.joints_.size());
    for (size_t j = 0; j < w.joints_.size(); ++j) warm.dims[j] = w.joints_[j]->dimension();
    warm.valid = true;
    w.forces_stale_ = true;  // lambda() solves on demand
  }
};

std::unique_ptr<World::IntegratorScheme> World::makeIntegratorScheme(Integrator kind) {
  switch (kind) {
    case Integrator::SymplecticEuler:
      return std::make_unique<SymplecticEulerScheme>();
    case Integrator::RK4:
      return std::make_unique<Rk4Scheme>();
    case Integrator::ImplicitEuler:
      return std::make_unique<ImplicitEulerScheme>();
    case Integrator::Rattle:
      break;
  }
  return std::make_unique<RattleScheme>();  // the default (an unknown value: validate() refuses it)
}

}  // namespace ponyhop

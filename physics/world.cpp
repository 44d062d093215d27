#include "physics/world.h"

#include <cmath>
#include <cstdio>

#include "physics/dense_solver.h"
#include "physics/rk4.h"
#include "physics/solver_factory.h"
#include "physics/stabilization.h"
#include "physics/symplectic_euler.h"
#include "physics/validate.h"

namespace ponyhop {

namespace {

constexpr double kHuge = 1e10;  // |x|, |v|, |w| beyond this: the run has diverged (cf. mj_checkPos)

bool finiteAndBounded(const Eigen::Vector3d& v) { return v.allFinite() && v.lpNorm<Eigen::Infinity>() < kHuge; }

}  // namespace

World::World(const PhysicsParams& params)
    : params_(params), solver_(makeConstraintSolver(params.solver)), reduced_(makeReducedSystem(params.solver)) {
  if (std::string e = validate(params_); !e.empty()) fail(e);
}

void World::fail(std::string message) {
  if (status_.empty()) status_ = std::move(message);
}

int World::addDynamicBody(RigidBody body) {
  body.kind = RigidBody::Kind::Dynamic;
  if (!(body.mass > 0.0) || !std::isfinite(body.mass) || !(body.inertia.minCoeff() > 0.0) ||
      !body.inertia.allFinite()) {
    fail("body '" + body.name + "': mass and inertia must be positive and finite");
  }
  body.q.normalize();
  bodies_.push_back(std::move(body));
  dynamic_.push_back(static_cast<int>(bodies_.size()) - 1);
  return static_cast<int>(bodies_.size()) - 1;
}

int World::addKinematicBody(KinematicMotion motion, std::string name) {
  RigidBody body;
  body.kind = RigidBody::Kind::Kinematic;
  body.name = std::move(name);
  body.motion = std::move(motion);
  if (body.motion) body.setKinematicState(body.motion(time_));
  bodies_.push_back(std::move(body));
  return static_cast<int>(bodies_.size()) - 1;
}

int World::addJoint(std::unique_ptr<Constraint> joint) {
  const auto dynamicOrNot = [&](int i) { return i != kWorldBody && i < bodyCount() && bodies_[i].isDynamic(); };
  const auto valid = [&](int i) { return i == kWorldBody || (i >= 0 && i < bodyCount()); };
  if (!valid(joint->bodyA()) || !valid(joint->bodyB())) {
    fail("joint " + std::to_string(joints_.size()) + " refers to a body that does not exist");
  } else if (!dynamicOrNot(joint->bodyA()) && !dynamicOrNot(joint->bodyB())) {
    fail("joint " + std::to_string(joints_.size()) + " joins two bodies whose motion is prescribed");
  }
  joints_.push_back(std::move(joint));
  return static_cast<int>(joints_.size()) - 1;
}

int World::addForceElement(std::unique_ptr<ForceElement> element) {
  forces_.push_back(std::move(element));
  return static_cast<int>(forces_.size()) - 1;
}

// ---------------------------------------------------------------------------------------------
// The step (Hecker, seed 000, "Simulation Loop - Control"; GUIDE: "the step reads like the
// method"). Each stage does nothing once the world has stopped, and stops it with a message when
// it produces a non-finite or runaway value.

void World::step() {
  if (!ok()) return;
  if (reduced_) {  // featherstone: joint-space steps replace the maximal-coordinate stages
    for (int i = 0; i < params_.substeps && ok(); ++i) reducedStep(params_.dt / params_.substeps);
    return;
  }
  const double h = params_.dt / params_.substeps;
  for (int i = 0; i < params_.substeps && ok(); ++i) substep(h);
}

void World::substep(double h) {
  updateKinematicBodies(time_);  // prescribed bodies: pose, velocity, acceleration at t
  applyExternalForces();         // gravity, joint damping, bending springs, air drag
  applyControllerForces();       // controller hook (empty for chains; the hopper adds one)
  solveJointForces();            // A lambda = b, F_c = J^T lambda, body accelerations
  integrate(h);                  // t += h (RK4 re-runs the four stages above at its stage times)
  stabilize();                   // projection onto C = 0 and J v = -J_k v_k (when chosen)
  resolveContacts();             // contact hook (none yet)
}

void World::updateKinematicBodies(double t) {
  stage_time_ = t;
  for (RigidBody& b : bodies_) {
    if (!b.isDynamic() && b.motion) b.setKinematicState(b.motion(t));
  }
}

void World::applyExternalForces() {
  const auto timed = clock_.time(Stage::ExternalForces);
  if (!ok()) return;
  for (RigidBody& b : bodies_) {
    b.force = b.isDynamic() ? Eigen::Vector3d(b.mass * params_.gravity) : Eigen::Vector3d::Zero();
    b.torque.setZero();
  }
  for (const auto& f : forces_) f->apply(bodies_);
  for (const RigidBody& b : bodies_) {
    if (!b.x.allFinite() || !b.q.coeffs().allFinite() || !b.v.allFinite() || !b.w.allFinite()) {
      return stop("external forces", "non-finite state of '" + b.name + "'",
                  "a prescribed motion returned NaN/inf, or the state was set to NaN from outside");
    }
    if (b.isDynamic() && (!b.force.allFinite() || !b.torque.allFinite())) {
      return stop("external forces", "non-finite force on '" + b.name + "'",
                  "a NaN/inf parameter (gravity, damping, stiffness, drag)");
    }
  }
}

void World::applyControllerForces() {
  const auto timed = clock_.time(Stage::Controller);
  if (!ok() || !controller_) return;
  controller_(stage_time_, bodies_);
  for (const RigidBody& b : bodies_) {
    if (b.isDynamic() && (!b.force.allFinite() || !b.torque.allFinite())) {
      return stop("controller forces", "non-finite force on '" + b.name + "'",
                  "the controller produced NaN/inf (division by a vanishing length or time?)");
    }
  }
}

void World::solveJointForces() {
  const auto timed = clock_.time(Stage::JointForces);
  if (!ok()) return;
  system_.evaluate(bodies_, joints_);
  BaumgarteGains gains;
  if (params_.stabilization == Stabilization::Baumgarte) gains = {params_.baumgarte_alpha, params_.baumgarte_beta};
  if (std::string e = solver_->solveJointForces(bodies_, system_, gains); !e.empty()) {
    return stop("joint forces", e,
                "redundant or duplicate joints, a joint between two prescribed bodies, or a zero mass or inertia");
  }
  checkBodies("joint forces", true);
}

void World::integrate(double h) {
  const auto timed = clock_.time(Stage::Integrate);
  if (!ok()) return;
  State state = gatherState();
  switch (params_.integrator) {
    case Integrator::SymplecticEuler:
      symplecticEulerStep(h, gatherAccelerations(), state);
      break;
    case Integrator::RK4:
      rk4Step(time_, h, gatherAccelerations(),
              [this](double t, const State& s, Accelerations& out) { accelerationsAt(t, s, out); }, state);
      break;
  }
  if (!ok()) return;  // a stage evaluation stopped the world
  time_ += h;
  scatterState(state);
  stage_time_ = time_;
  checkBodies("integrate", false);
}

void World::stabilize() {
  const auto timed = clock_.time(Stage::Stabilize);
  if (!ok() || params_.stabilization != Stabilization::Projection || joints_.empty()) return;
  updateKinematicBodies(time_);
  const ProjectionResult r = projectPositions(bodies_, joints_, system_, *solver_);
  if (!r.problem.empty() || !(r.error < 1e-6)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, " (joint error %.3g m after %d iterations)", r.error, r.iterations);
    return stop("stabilize", (r.problem.empty() ? std::string("position projection failed") : r.problem) + buf,
                "the joints were pulled far apart within one step: reduce dt or raise substeps");
  }
  if (std::string e = ponyhop::projectVelocities(bodies_, joints_, system_, *solver_); !e.empty()) {
    return stop("stabilize", e, "redundant or duplicate joints");
  }
  checkBodies("stabilize", false);
}

void World::resolveContacts() {
  const auto timed = clock_.time(Stage::Contact);
  if (!ok() || !contact_) return;
  contact_(time_, bodies_);
  checkBodies("contact", false);
}

// Featherstone (physics.solver = featherstone; physics/featherstone.h, docs/SOLVERS.md). The
// state lives in joint coordinates; one reduced step replaces the joint-force, integrate and
// stabilize stages (joints hold by construction: stabilization has nothing to do) and reuses the
// kinematic, external and controller force stages at every evaluation; then the contact hook.
// h = 0: evaluate only (ABA at the current state). params.substeps equal steps per dt.

void World::reducedStep(double h) {
  const ReducedHooks hooks{[this](double t) { updateKinematicBodies(t); }, [this] {
                             applyExternalForces();
                             applyControllerForces();
                             return ok();
                           }};
  std::string e = reduced_->build(bodies_, joints_);
  if (e.empty()) {
    e = h > 0.0 ? reduced_->step(time_, h, params_.integrator, bodies_, hooks) : reduced_->evaluate(time_, bodies_, hooks);
  }
  if (!e.empty()) {
    return stop("reduced step", e, "the scene needs what reduced coordinates cannot express (docs/SOLVERS.md)");
  }
  if (!ok() || h == 0.0) return;
  time_ += h;
  stage_time_ = time_;
  if (checkBodies("reduced step", false)) resolveContacts();
}

// ---------------------------------------------------------------------------------------------

void World::accelerationsAt(double t, const State& state, Accelerations& out) {
  scatterState(state);
  updateKinematicBodies(t);
  applyExternalForces();
  applyControllerForces();
  solveJointForces();
  out = gatherAccelerations();
}

void World::evaluate() {
  if (!ok()) return;
  if (reduced_) return reducedStep(0.0);  // featherstone: ABA at the current state
  updateKinematicBodies(time_);
  applyExternalForces();
  applyControllerForces();
  solveJointForces();
}

void World::projectVelocities() {
  if (!ok()) return;
  updateKinematicBodies(time_);
  if (std::string e = ponyhop::projectVelocities(bodies_, joints_, system_, *solver_); !e.empty()) {
    stop("velocity projection", e, "redundant or duplicate joints");
  }
}

State World::gatherState() const {
  State s(dynamic_.size());
  for (size_t k = 0; k < dynamic_.size(); ++k) {
    const RigidBody& b = bodies_[dynamic_[k]];
    s[k] = {b.x, b.q, b.v, b.w};
  }
  return s;
}

void World::scatterState(const State& state) {
  for (size_t k = 0; k < dynamic_.size(); ++k) {
    RigidBody& b = bodies_[dynamic_[k]];
    b.x = state[k].x;
    b.q = state[k].q.normalized();  // RK4 stage quaternions are not unit
    b.v = state[k].v;
    b.w = state[k].w;
  }
}

Accelerations World::gatherAccelerations() const {
  Accelerations a(dynamic_.size());
  for (size_t k = 0; k < dynamic_.size(); ++k) a[k] = {bodies_[dynamic_[k]].a, bodies_[dynamic_[k]].alpha};
  return a;
}

bool World::checkBodies(const char* stage, bool accelerations) {
  for (int i : dynamic_) {
    const RigidBody& b = bodies_[i];
    if (accelerations) {
      if (!b.a.allFinite() || !b.alpha.allFinite() || !b.constraint_force.allFinite()) {
        stop(stage, "non-finite acceleration of '" + b.name + "'",
             "an ill-conditioned constraint matrix (tiny masses or inertias next to large ones)");
        return false;
      }
    } else if (!finiteAndBounded(b.x) || !b.q.coeffs().allFinite() || !finiteAndBounded(b.v) ||
               !finiteAndBounded(b.w)) {
      stop(stage, "non-finite or runaway state of '" + b.name + "'",
           "the time step is too large for the motion (stiff springs or damping, a whipping tip): "
           "reduce dt or raise substeps");
      return false;
    }
  }
  return true;
}

void World::stop(const char* stage, const std::string& what, const char* cause) {
  char when[64];
  std::snprintf(when, sizeof when, "t = %.6g s", stage_time_);
  fail(std::string(when) + ", stage '" + stage + "': " + what + ". Likely cause: " + cause + ".");
}

// ---------------------------------------------------------------------------------------------

double World::kineticEnergy() const {
  double e = 0.0;
  for (int i : dynamic_) e += bodies_[i].kineticEnergy();
  return e;
}

double World::potentialEnergy() const {
  double e = 0.0;
  for (int i : dynamic_) e -= bodies_[i].mass * params_.gravity.dot(bodies_[i].x);
  for (const auto& f : forces_) e += f->potentialEnergy(bodies_);
  return e - potential_reference_;
}

double World::maxJointError() const {
  ConstraintSystem s;
  s.evaluate(bodies_, joints_);
  return s.maxError();
}

double World::constraintPower() const {
  double p = 0.0;
  for (int i : dynamic_) p += bodies_[i].constraint_force.dot(bodies_[i].v) + bodies_[i].constraint_torque.dot(bodies_[i].w);
  return p;
}

}  // namespace ponyhop

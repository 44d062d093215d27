#include "physics/world.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <utility>

#include "physics/integrator_scheme.h"
#include "physics/solver_factory.h"
#include "physics/stabilization.h"
#include "physics/validate.h"

namespace ponyhop {

using checks::finite;
using checks::finiteAndBounded;

namespace {

// The rotation limit splits substeps (step control by the turn per step, not by a tolerance).
bool splitsOnRotation(const PhysicsParams& p) { return p.max_step_rotation > 0.0 && p.tolerance <= 0.0; }

// A substep in which a body turned more than this times max_step_rotation is undone and split
// (not under the count from both ends: World::takeStep).
// 1.25, not 2: the energy error follows the largest turns (docs/STABILITY.md, "The default and
// why"), and the whip speeds up within a dt, so a looser split let single substeps turn up to
// twice the limit.
constexpr double kSplitRotation = 1.25;
constexpr int kMaxSplits = 10;  // a substep is split in two at most this deep (1/1024 of it)
// physics.tolerance is the position error allowed per this much simulated time (s): a substep of
// h may add tolerance h / kToleranceHorizon (advanceToTolerance).
constexpr double kToleranceHorizon = 1.0;
// A prescribed pose this far from its own prediction over one step is a jump (followTeleports).
constexpr double kTeleportDistance = 1e-2;  // m
constexpr double kTeleportAngle = 0.1;      // rad
// tan(kTeleportAngle / 2)^2 (tan(0.05) = 0.05004170837553879...).
constexpr double kTanHalfTeleportAngle = 0.05004170837553879;
constexpr double kTanHalfTeleportAngle2 = kTanHalfTeleportAngle * kTanHalfTeleportAngle;
// The constant follows the angle: tan's series to x^9 (std::tan is not constexpr).
constexpr double tanSeries(double x) {
  const double x2 = x * x;
  return x * (1.0 + x2 * (1.0 / 3.0 + x2 * (2.0 / 15.0 + x2 * (17.0 / 315.0 + x2 * 62.0 / 2835.0))));
}
static_assert(tanSeries(kTeleportAngle / 2) - kTanHalfTeleportAngle < 1e-15 &&
                  kTanHalfTeleportAngle - tanSeries(kTeleportAngle / 2) < 1e-15,
              "kTanHalfTeleportAngle is tan(kTeleportAngle / 2)");

// 0 when every entry of v is finite, else NaN (x - x is NaN for an inf or NaN x, +0 otherwise;
// a sum with a NaN is NaN): the test of a body's 13 state entries as subtractions and additions
// and one branch instead of a test and branch per entry.
template <class V>
double nanUnlessFinite(const V& v) {
  double z = v(0) - v(0);
  for (int i = 1; i < v.size(); ++i) z += v(i) - v(i);
  return z;
}

// What World::checkForces tests, inlined into the external-force stage's pass over the bodies
// (as a call per body it was 3 % of a tree step at N = 8); checkForces names the body and stops.
[[gnu::always_inline]] inline bool stateAndForcesFinite(const RigidBody& b) {
  return nanUnlessFinite(b.x) + nanUnlessFinite(b.q.coeffs()) + (nanUnlessFinite(b.v) + nanUnlessFinite(b.w)) == 0.0 &&
         (!b.isDynamic() || nanUnlessFinite(b.force) + nanUnlessFinite(b.torque) == 0.0);
}

}  // namespace

World::World(const PhysicsParams& params)
    : params_(params),
      solver_(makeConstraintSolver(params.solver)),
      reduced_(makeReducedSystem(params.solver)),
      scheme_(makeIntegratorScheme(params.integrator)) {
  if (Status s = validate(params_); !s.ok()) fail(s.message());
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

void World::fail(std::string message) {
  if (state_.status.empty()) state_.status = std::move(message);
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
  if (body.motion) body.setKinematicState(body.motion(state_.time));
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

void World::addController(std::shared_ptr<Controller> controller) { controllers_.push_back(std::move(controller)); }

void World::addContactSet(std::shared_ptr<ContactSet> contacts) { contacts_.push_back(std::move(contacts)); }

int World::addForceElement(std::unique_ptr<ForceElement> element) {
  forces_.push_back(std::move(element));
  return static_cast<int>(forces_.size()) - 1;
}

// ---------------------------------------------------------------------------------------------
// The step (Hecker lecture, "Simulation Loop - Control"), one named stage a line as MuJoCo's
// mj_step reads. Each stage does nothing once the world has stopped, and stops it with a message
// when it produces a non-finite or runaway value.

void World::step() {
  if (!ok()) return;
  think();  // controllers' state machines: setpoints for this step (Think, Hecker lecture)
  if (!ok()) return;
  last_substeps_ = 0;
  last_error_ = 0.0;
  if (params_.tolerance > 0.0) {
    // Accuracy asked for: start from the last dt's count (coarser when it was well inside its
    // budget), split by step doubling.
    last_error_ratio_ = 0.0;
    int n = std::max(params_.substeps, state_.tolerance_substeps);
    const double h = params_.dt / n;
    for (int i = 0; i < n && ok(); ++i) advanceToTolerance(h, 0);
    // A local error of order p + 1 grows 2^(p+1) x when the substep doubles and its budget
    // (tolerance h / 1 s) 2x: coarser only when 2^p x the largest share (with a margin of 2) still fits.
    const int coarse = std::max(1, last_substeps_ / 2);
    const double growth = 2.0 * std::ldexp(1.0, methodOrder());
    state_.tolerance_substeps = last_error_ratio_ < 1.0 / growth ? std::max(1, coarse / 2) : coarse;
    return;
  }
  // Enough substeps that the fastest body turns at most max_step_rotation per substep at the
  // start of dt; substep() splits further when the motion speeds up within dt (not RATTLE: there
  // the count holds at the end of the dt as well, below, and nothing is split for its turn).
  const double theta = params_.max_step_rotation * std::numbers::pi / 180.0;
  const auto count = [&](double speed) {
    return std::max(params_.substeps,
                    theta > 0.0 ? static_cast<int>(std::min(4096.0, std::ceil(params_.dt * speed / theta))) : 1);
  };
  int n = theta > 0.0 ? count(maxAngularSpeed()) : count(0.0);  // no turn limit: no speeds (8 norms at N = 8)
  // RATTLE: the count must also hold at the end of dt, or the dt is taken again with the end's
  // count (once). A count from the start alone is not time-symmetric, and a reversible method
  // with such steps loses its bounded energy error: the whipping chain's energy fell 0.05 % of E0
  // per simulated second. With both ends, 0.06-0.33 % after 60 s (docs/STABILITY.md).
  const bool symmetric = theta > 0.0 && symmetricCount();
  if (symmetric) saveStateInto(dt_start_);
  for (bool redone = false;; redone = true) {
    const double h = params_.dt / n;
    for (int i = 0; i < n && ok(); ++i) substep(h);
    if (!symmetric || redone || !ok()) return;
    const int n_end = count(maxAngularSpeed());
    if (n_end <= n) return;
    restoreState(dt_start_);
    last_substeps_ = 0;
    n = n_end;
  }
}

// One substep: stages 1-6, then contacts. When a stage asks for it (RATTLE's position solve did
// not converge, or, without the count from both ends, a body turned more than kSplitRotation
// max_step_rotation) the substep is undone and taken as two half steps instead, up to kMaxSplits times.
void World::substep(double h, int depth) {
  if (substep_starts_.empty()) substep_starts_.resize(kMaxSplits + 1);  // never resized again
  Snapshot& start = substep_starts_[depth];
  // The snapshot (every body's state and the stability monitor's, 3-5 % of a fixed step) only
  // when the substep can be undone: a contact set may report an impact inside it, the rotation
  // limit may split it, RATTLE or implicit Euler may fail and ask for halves. Otherwise a step
  // that fails has stopped the world, and nothing is restored.
  const bool undoable = !contacts_.empty() || splitsOnRotation(params_) || scheme_->mayFail() || shakes();
  if (undoable) snapshotInto(start);
  const bool stepped = takeStep(h);
  if (stepped && depth < kMaxSplits && impactInside()) {
    restore(start);  // a contact began inside the substep: bisect towards it
    substep(0.5 * h, depth + 1);
    if (ok()) substep(0.5 * h, depth + 1);
    return;
  }
  if (!stepped) {
    if (!ok()) return;
    if (depth < kMaxSplits && undoable) {
      restore(start);
      substep(0.5 * h, depth + 1);
      if (ok()) substep(0.5 * h, depth + 1);
      return;
    }
    return stop("integrate", split_reason_ + " even with the step split " + std::to_string(kMaxSplits) + " times",
                "the joints were pulled apart faster than any step can follow (a teleported kinematic parent, "
                "an extreme mass ratio, NaN-free but runaway forces): check the prescribed motion and parameters");
  }
  resolveContacts();  // contact sets (the hopper's foot: an active set)
  ++last_substeps_;
}

bool World::takeStep(double h) {
  split_reason_.clear();
  if (reduced_) {
    reducedStep(h);  // featherstone: one joint-space step replaces the method's stages
  } else {
    scheme_->takeStep(*this, h);  // the method's stages (physics/integrator_scheme.cpp)
  }
  // Not under the count from both ends (RATTLE): there a substep is never split for its turn.
  // The split is decided at the substep's end alone, so the reverse step would not make it: the
  // steps stop being time-symmetric and the energy error grows (the 8-link chain at dt 1/60: 1.0 %
  // after 60 s, 5.3 % after 300 s; without the split 0.12 % for both; docs/STABILITY.md).
  if (ok() && split_reason_.empty() && splitsOnRotation(params_) && !symmetricCount()) {
    const double turned = h * maxAngularSpeed();
    if (turned > kSplitRotation * params_.max_step_rotation * std::numbers::pi / 180.0) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "a body turned %.3g deg in one step", turned * 180.0 / std::numbers::pi);
      split_reason_ = buf;
    }
  }
  return ok() && split_reason_.empty();
}

// Step doubling (Hairer, Norsett & Wanner I, II.4): one step of h and two of h/2 from the same
// state; their difference estimates the error of the single step (the two half steps, which are
// kept, are ~4x more accurate for a second-order method). The budget of a substep is its share
// of the run, tolerance h / (1 s) (error per unit step, Shampine): the local errors of one
// simulated second add up to at most the tolerance, so the global error over that second is the
// tolerance, not the tolerance per substep (which grew with the substep count: 2.2e-5 m achieved
// for 1e-6 asked on the 8-link chain). Too large: both are undone and each half is taken the
// same way. Contacts run only after an accepted pair (their state is not undone); a touchdown
// inside the pair bisects it as substep() does.
void World::advanceToTolerance(double h, int depth) {
  const Snapshot start = snapshot();
  const bool coarse_ok = takeStep(h);
  const State coarse = gatherState();
  restore(start);
  bool fine_ok = takeStep(0.5 * h);
  if (fine_ok) fine_ok = takeStep(0.5 * h);
  // The kept pair's error (Richardson): a method of order p makes the single step's error 2^p
  // times the pair's, so the difference is (2^p - 1) times the pair's error.
  const double err = coarse_ok && fine_ok
                         ? errorDistance(coarse, gatherState()) / (std::ldexp(1.0, methodOrder()) - 1.0)
                         : std::numeric_limits<double>::infinity();
  const double budget = params_.tolerance * h / kToleranceHorizon;
  if (depth < kMaxSplits && (err > budget || (fine_ok && impactInside()))) {
    restore(start);
    advanceToTolerance(0.5 * h, depth + 1);
    if (ok()) advanceToTolerance(0.5 * h, depth + 1);
    return;
  }
  if (!fine_ok) {
    if (ok()) {
      stop("integrate", split_reason_ + " even with the step split " + std::to_string(kMaxSplits) + " times",
           "the joints were pulled apart faster than any step can follow");
    }
    return;
  }
  if (err > budget) ++tolerance_misses_;  // the deepest split still misses: counted, not hidden
  last_error_ = std::max(last_error_, err);
  last_error_ratio_ = std::max(last_error_ratio_, err / budget);
  error_sum_ += err;
  resolveContacts();
  last_substeps_ += 2;
}

// A kinematic body whose pose at t + h is far from what its own velocity and acceleration at t
// predict (x + h v + h^2/2 a) was moved without a consistent velocity: a teleport. Integrating
// through it would fling what hangs from it (the gap closed within one step is a velocity of
// gap / h). Instead the dynamic bodies joined to it (through joints, not through other prescribed
// bodies) are carried along by the same rigid jump, velocities rotated with it: a teleported head
// takes its ponytail along. Smooth motions predict within O(h^3 jerk) and are left alone.
namespace {
// Zero velocities and accelerations (exactly).
template <class S>
bool restingState(const S& s) {
  return s.v.isZero(0.0) && s.a.isZero(0.0) && s.w.isZero(0.0) && s.alpha.isZero(0.0);
}
}  // namespace

void World::followTeleports(double h) {
  if (!ok()) return;
  for (size_t k = 0; k < bodies_.size(); ++k) {
    const RigidBody& parent = bodies_[k];
    if (parent.isDynamic() || !parent.motion) continue;
    const KinematicState next = parent.motion(state_.time + h);
    // At rest and staying where it is (a fixed anchor): the prediction below is its pose exactly
    // (h times zeros added, the identity turn), so it is no teleport. Decided without the
    // prediction's quaternion products and normalization (2 % of a tree step at N = 8).
    if (next.x == parent.x && next.q.coeffs() == parent.q.coeffs() && restingState(parent) && restingState(next))
      continue;
    const Eigen::Vector3d x_pred = parent.x + h * parent.v + 0.5 * h * h * parent.a;
    const Eigen::Quaterniond q_pred =
        quaternionFromRotationVector(h * parent.w + 0.5 * h * h * parent.alpha) * parent.q;
    // The jump's rotation, not yet normalized: its angle 2 atan(|vec| / |w|) does not depend on
    // its length, and it is finite exactly when its normalization is. Below kTeleportAngle when
    // |vec| < tan(kTeleportAngle / 2) |w| (no normalization, sqrt of the angle or atan2 per
    // step, 1-2 % of a tree step at N = 8 with its fixed anchor).
    const Eigen::Quaterniond turn = next.q.normalized() * q_pred.conjugate();
    if (!next.x.allFinite() || !turn.coeffs().allFinite()) continue;  // the external-force check reports it
    if ((next.x - x_pred).norm() < kTeleportDistance &&
        turn.vec().squaredNorm() < kTanHalfTeleportAngle2 * (turn.w() * turn.w()))
      continue;
    const Eigen::Quaterniond jump = turn.normalized();
    // The dynamic bodies reachable from k through joints.
    std::vector<char> carried(bodies_.size(), 0);
    std::vector<int> todo{static_cast<int>(k)};
    while (!todo.empty()) {
      const int b = todo.back();
      todo.pop_back();
      for (const auto& j : joints_) {
        const int other = j->bodyA() == b ? j->bodyB() : j->bodyB() == b ? j->bodyA() : kWorldBody;
        if (other == kWorldBody || carried[other] || !bodies_[other].isDynamic()) continue;
        carried[other] = 1;
        todo.push_back(other);
      }
    }
    for (size_t i = 0; i < bodies_.size(); ++i) {
      if (!carried[i]) continue;
      RigidBody& b = bodies_[i];
      b.x = next.x + jump * (b.x - x_pred);
      b.q = (jump * b.q).normalized();
      b.v = jump * b.v;
      b.w = jump * b.w;
    }
  }
}

void World::snapshotInto(Snapshot& s) const {
  gatherStateInto(s.bodies);
  s.step = state_;  // the warm start has the same rows as last time: copied without allocating
}

void World::restore(const Snapshot& s) {
  gathered_ = false;
  scatterState(s.bodies);
  // Its warm start is the multipliers of the last step before the snapshot: a force, so as good
  // a guess for a retry with h / 2 as for h; the undone step's never seed anything. Its status
  // is "": only called on a world that was running when the snapshot was taken.
  state_ = s.step;
  stage_time_ = state_.time;
  forces_stale_ = true;
  split_reason_.clear();
}

int World::methodOrder() const { return scheme_->order(); }

bool World::symmetricCount() const { return scheme_->symmetricCount() && !reduced_; }

bool World::warmStartFits() const {
  if (!state_.warm_start.valid || state_.warm_start.dims.size() != joints_.size()) return false;
  for (size_t j = 0; j < joints_.size(); ++j)
    if (state_.warm_start.dims[j] != joints_[j]->dimension()) return false;
  return true;
}

bool World::velocityDependentForces() const {
  for (const auto& f : forces_)
    if (f->dependsOnVelocity()) return true;
  for (const auto& c : controllers_)
    if (c->dependsOnVelocity()) return true;
  return false;
}

const Eigen::VectorXd& World::lambda() {
  if (forces_stale_ && ok() && !reduced_) evaluate();  // featherstone keeps its own
  return solver_->lambda();
}

double World::errorDistance(const State& a, const State& b) const {
  // Centre distance plus the turn times the radius of gyration: how far points of the body (at
  // a typical distance from its centre) moved apart, in metres. Plus the same of the velocities
  // times kToleranceHorizon: a velocity error carries the positions apart for the rest of the
  // second the tolerance is per (the position part alone missed the shaken chain's error 10x).
  double d = 0.0;
  for (size_t k = 0; k < dynamic_.size(); ++k) {
    const RigidBody& body = bodies_[dynamic_[k]];
    const double radius = std::sqrt(body.inertia.maxCoeff() / body.mass);
    const double position = (a[k].x - b[k].x).norm() + radius * rotationVector(a[k].q * b[k].q.conjugate()).norm();
    const double velocity = (a[k].v - b[k].v).norm() + radius * (a[k].w - b[k].w).norm();
    d = std::max(d, position + kToleranceHorizon * velocity);
  }
  return d;
}

double World::maxAngularSpeed() const {
  double w = 0.0;
  for (int i : dynamic_) w = std::max(w, bodies_[i].w.norm());
  return std::isfinite(w) ? w : 0.0;
}

void World::watchStability(double h) {
  const double limit = scheme_->stabilityLimit();
  if (!ok() || limit == 0.0) return;  // a method stable for any step is not watched
  if (scheme_->observesInPlace()) {
    // Read in place: integrate() steps the bodies in place, no gathered copy needed.
    if (!state_.monitor.observe(h, bodies_, dynamic_, limit)) return;
  } else {
    gatherStateInto(state_scratch_);
    gatherAccelerationsInto(acc_scratch_);
    gathered_ = true;  // integrate() steps from these (nothing moves the bodies in between)
    if (!state_.monitor.observe(h, state_scratch_, acc_scratch_, limit)) return;
  }
  char what[160];
  std::snprintf(what, sizeof what,
                "the step is unstable: h rho = %.3g > %.3g (stiffness estimate rho = %.3g 1/s) and the state "
                "increments grew %.3gx per step",
                state_.monitor.hRho(), limit, state_.monitor.hRho() / h, state_.monitor.growth());
  std::string cause = "an explicit integrator (" + std::string(enumName(scheme_->kind())) +
                      ") on forces too stiff for the step (stiff springs, servos, stops or damping): reduce dt, raise "
                      "substeps, or use integrator = implicit_euler";
  stop("integrate", what, cause.c_str());
}

void World::think() {
  for (const auto& c : controllers_) c->think(*this);
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
  // Without force elements the accumulators are set and checked in one pass over the bodies.
  const bool elements = !forces_.empty();
  for (RigidBody& b : bodies_) {
    b.force = b.isDynamic() ? Eigen::Vector3d(b.mass * params_.gravity) : Eigen::Vector3d::Zero();
    b.torque.setZero();
    if (!elements && !stateAndForcesFinite(b) && !checkForces(b)) return;
  }
  if (!elements) return;
  for (const auto& f : forces_) f->apply(bodies_);
  for (const RigidBody& b : bodies_) {
    if (!stateAndForcesFinite(b) && !checkForces(b)) return;
  }
}

bool World::checkForces(const RigidBody& b) {
  if (!(nanUnlessFinite(b.x) + nanUnlessFinite(b.q.coeffs()) + (nanUnlessFinite(b.v) + nanUnlessFinite(b.w)) == 0.0)) {
    stop("external forces", "non-finite state of '" + b.name + "'",
         "a prescribed motion returned NaN/inf, or the state was set to NaN from outside");
    return false;
  }
  if (b.isDynamic() && !(nanUnlessFinite(b.force) + nanUnlessFinite(b.torque) == 0.0)) {
    stop("external forces", "non-finite force on '" + b.name + "'",
         "a NaN/inf parameter (gravity, damping, stiffness, drag)");
    return false;
  }
  return true;
}

void World::applyControllerForces() {
  // An empty stage is not timed: its two clock reads would cost more than its work.
  if (!ok() || controllers_.empty()) return;
  const auto timed = clock_.time(Stage::Controller);
  for (const auto& c : controllers_) c->applyForces(*this, stage_time_);
  for (const RigidBody& b : bodies_) {
    if (b.isDynamic() && (!finite(b.force) || !finite(b.torque))) {
      return stop("controller forces", "non-finite force on '" + b.name + "'",
                  "the controller produced NaN/inf (division by a vanishing length or time?)");
    }
  }
}

void World::solveJointForces() {
  const auto timed = clock_.time(Stage::JointForces);
  if (!ok()) return;
  BaumgarteGains gains;
  if (params_.stabilization == Stabilization::Baumgarte) gains = {params_.baumgarte_alpha, params_.baumgarte_beta};
  if (params_.stabilization == Stabilization::Velocity && force_step_ > 0.0) {
    // J a = -J v / h - erp C / h^2, so that v' = v + h a has J v' = -erp C / h (docs/PHYSICS.md).
    gains = {0.5 / force_step_, std::sqrt(params_.erp) / force_step_, true};
  }
  // The velocity-level solve reads no J'q': the joints may skip it.
  system_.evaluate(bodies_, joints_, !gains.velocity_level);
  if (Status s = solver_->solveJointForces(bodies_, system_, gains); !s.ok()) {
    return stop("joint forces", s.message(),
                "redundant or duplicate joints, a joint between two prescribed bodies, or a zero mass or inertia");
  }
  // The per-body check (to name the body and stop) only when the solve saw a non-finite value.
  if (solver_->accelerationsFinite() || checkBodies("joint forces", true)) forces_stale_ = false;
}

void World::integrate(double h) {
  const auto timed = clock_.time(Stage::Integrate);
  const bool gathered = std::exchange(gathered_, false);
  if (!ok()) return;
  scheme_->integrate(*this, h, gathered);
}

ConstrainedStep World::constrainedStep() {
  return {bodies_,
          joints_,
          system_,
          *solver_,
          [this](double t) {
            updateKinematicBodies(t);
            applyExternalForces();
            applyControllerForces();
            return ok();
          },
          [this](double t) { updateKinematicBodies(t); }};
}

bool World::finishConstrainedStep(const ConstrainedStepResult& r, double h) {
  if (!ok()) return false;
  if (r.failed) {
    split_reason_ = r.problem.data();  // substep() undoes the step and tries two halves
    return false;
  }
  state_.time += h;
  stage_time_ = state_.time;
  checkBodies("integrate", false);
  return true;
}

bool World::shakes() const {
  return !reduced_ && scheme_->kind() == Integrator::SymplecticEuler &&
         params_.stabilization == Stabilization::Projection && !joints_.empty();
}

void World::stabilize() {
  if (!ok() || !split_reason_.empty()) return;
  if (params_.stabilization != Stabilization::Projection || joints_.empty()) return;
  const auto timed = clock_.time(Stage::Stabilize);
  updateKinematicBodies(state_.time);
  // After symplectic Euler: its constrained form (the impulse along J(q_n), into the velocity too);
  // after the other methods: post-stabilization along the end point's directions.
  const bool shake = shakes();
  const ProjectionResult r = shake ? shakePositions(bodies_, joints_, system_, *solver_, shake_work_, shake_work_.h)
                                   : projectPositions(bodies_, joints_, system_, *solver_, projection_work_);
  if (r.status.ok() && !r.converged && shake) {
    // The chord iteration did not contract (a link turned far within the step): the substep is
    // undone and taken as two halves, as RATTLE's is.
    char buf[112];
    std::snprintf(buf, sizeof buf, "symplectic Euler's position solve did not converge (joint error %.3g m)", r.error);
    split_reason_ = buf;
    return;
  }
  if (!r.status.ok() || !(r.error < 1e-6)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, " (joint error %.3g m after %d iterations)", r.error, r.iterations);
    return stop("stabilize", (r.status.ok() ? std::string("position projection failed") : r.status.message()) + buf,
                "the joints were pulled far apart within one step (a step too large for stiff springs or a "
                "fast whip): reduce dt or raise substeps, or use integrator = implicit_euler for stiff springs");
  }
  if (Status s = ponyhop::projectVelocities(bodies_, joints_, system_, *solver_, projection_work_); !s.ok()) {
    return stop("stabilize", s.message(), "redundant or duplicate joints");
  }
  // projectVelocities factored A at these poses and moved no body.
  stabilized_generation_ = solver_->generation();
  stabilized_x_.resize(bodies_.size());
  stabilized_q_.resize(bodies_.size());
  for (size_t i = 0; i < bodies_.size(); ++i) {
    stabilized_x_[i] = bodies_[i].x;
    stabilized_q_[i] = bodies_[i].q;
  }
  checkBodies("stabilize", false);
}

const ConstraintSolver* World::solverFactoredAt(const std::vector<RigidBody>& bodies) const {
  if (stabilized_generation_ == 0 || solver_->generation() != stabilized_generation_ ||
      bodies.size() != stabilized_x_.size())
    return nullptr;
  for (size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].x != stabilized_x_[i] || bodies[i].q.coeffs() != stabilized_q_[i].coeffs()) return nullptr;
  return solver_.get();
}

bool World::impactInside() const {
  for (const auto& c : contacts_)
    if (c->impactInside(*this)) return true;
  return false;
}

void World::resolveContacts() {
  if (!ok() || contacts_.empty()) return;  // nothing to do: not timed
  const auto timed = clock_.time(Stage::Contact);
  for (const auto& c : contacts_) c->update(*this);
  checkBodies("contact", false);
}

// ---------------------------------------------------------------------------------------------
// Featherstone (physics.solver = featherstone; physics/featherstone.h, docs/SOLVERS.md). The
// state lives in joint coordinates; one reduced step replaces the joint-force, integrate and
// stabilize stages (joints hold by construction: stabilization has nothing to do) and reuses the
// kinematic, external and controller force stages at every evaluation. It is taken by
// takeStep(), so substeps, max_step_rotation and tolerance choose h as for the other solvers.
// h = 0: evaluate only (ABA at the current state).

void World::reducedStep(double h) {
  // ABA and the joint-space integration: one stage, charged to joint forces.
  const auto timed = clock_.time(Stage::JointForces);
  const ReducedHooks hooks{[this](double t) { updateKinematicBodies(t); },
                           [this] {
                             applyExternalForces();
                             applyControllerForces();
                             return ok();
                           }};
  Status s = reduced_->build(bodies_, joints_);
  if (s.ok() && params_.adaptive_joints > reduced_->jointCount()) {
    s = Status::error("physics.adaptive_joints = " + std::to_string(params_.adaptive_joints) + " is more than the " +
                      std::to_string(reduced_->jointCount()) + " joints of the scene (0 to " +
                      std::to_string(reduced_->jointCount()) + ")");
  }
  if (s.ok() && reduced_->loopRows() > 0 && (params_.adaptive_joints > 0 || params_.adaptive_tolerance > 0.0)) {
    s = Status::error(
        "adaptive dynamics (physics.adaptive_joints, physics.adaptive_tolerance) cannot take a closed "
        "loop: set both to 0 for this scene");
  }
  if (s.ok()) {
    reduced_->setAdaptive(params_.adaptive_joints, params_.adaptive_tolerance);
    reduced_->setLoopStabilization(params_.stabilization, params_.baumgarte_alpha, params_.baumgarte_beta);
    s = h > 0.0 ? reduced_->step(state_.time, h, scheme_->kind(), bodies_, hooks)
                : reduced_->evaluate(state_.time, bodies_, hooks);
  }
  if (!s.ok()) {
    return stop("reduced step", s.message(),
                "the scene needs what reduced coordinates cannot express (docs/SOLVERS.md)");
  }
  if (!ok() || h == 0.0) return;
  state_.time += h;
  stage_time_ = state_.time;
  checkBodies("reduced step", false);
}

// ---------------------------------------------------------------------------------------------

void World::accelerationsAt(double t, const State& state, Accelerations& out) {
  scatterState(state);
  updateKinematicBodies(t);
  applyExternalForces();
  applyControllerForces();
  solveJointForces();
  gatherAccelerationsInto(out);
}

void World::evaluate() {
  if (!ok()) return;
  if (reduced_) return reducedStep(0.0);  // featherstone: ABA at the current state
  updateKinematicBodies(state_.time);
  applyExternalForces();
  applyControllerForces();
  solveJointForces();
}

void World::projectVelocities() {
  if (!ok()) return;
  updateKinematicBodies(state_.time);
  if (Status s = projectVelocitiesOntoJoints(); !s.ok())
    stop("velocity projection", s.message(), "redundant or duplicate joints");
}

ProjectionResult World::projectPositionsOntoJoints() {
  return ponyhop::projectPositions(bodies_, joints_, system_, *solver_, projection_work_);
}

ProjectionResult World::assembleJoints() {
  return ponyhop::projectPositions(bodies_, joints_, system_, *solver_, 1e-12, 1000, 0.01);
}

Status World::projectVelocitiesOntoJoints(Eigen::VectorXd* impulses) {
  return ponyhop::projectVelocities(bodies_, joints_, system_, *solver_, projection_work_, impulses);
}

World::SavedState World::saveState() const {
  SavedState s;
  saveStateInto(s);
  return s;
}

void World::saveStateInto(SavedState& s) const {
  s.bodies.resize(bodies_.size());  // the storage s already has: no allocation once sized
  for (size_t i = 0; i < bodies_.size(); ++i) s.bodies[i] = bodies_[i].state();
  s.controllers.resize(controllers_.size());
  for (size_t i = 0; i < controllers_.size(); ++i) s.controllers[i] = controllers_[i]->saveState();
  s.contacts.resize(contacts_.size());
  for (size_t i = 0; i < contacts_.size(); ++i) s.contacts[i] = contacts_[i]->saveState();
  s.step = state_;
}

void World::restoreState(const SavedState& s) {
  gathered_ = false;
  for (size_t i = 0; i < bodies_.size() && i < s.bodies.size(); ++i) bodies_[i].state() = s.bodies[i];
  for (size_t i = 0; i < controllers_.size() && i < s.controllers.size(); ++i)
    controllers_[i]->restoreState(s.controllers[i]);
  for (size_t i = 0; i < contacts_.size() && i < s.contacts.size(); ++i) contacts_[i]->restoreState(s.contacts[i]);
  state_ = s.step;
  stage_time_ = state_.time;
  forces_stale_ = true;
  split_reason_.clear();
}

State World::gatherState() const {
  State s;
  gatherStateInto(s);
  return s;
}

void World::gatherStateInto(State& s) const {
  s.resize(dynamic_.size());
  for (size_t k = 0; k < dynamic_.size(); ++k) s[k] = bodies_[dynamic_[k]].state();
}

void World::scatterState(const State& state) {
  for (size_t k = 0; k < dynamic_.size(); ++k) {
    BodyState& s = bodies_[dynamic_[k]].state();
    s = state[k];
    s.q.normalize();  // RK4 stage quaternions are not unit
  }
}

void World::gatherAccelerationsInto(Accelerations& a) const {
  a.resize(dynamic_.size());
  for (size_t k = 0; k < dynamic_.size(); ++k) a[k] = {bodies_[dynamic_[k]].a, bodies_[dynamic_[k]].alpha};
}

bool World::checkBodies(const char* stage, bool accelerations) {
  for (int i : dynamic_) {
    const RigidBody& b = bodies_[i];
    if (accelerations) {
      if (!finite(b.a) || !finite(b.alpha) || !finite(b.constraint_force)) {
        stop(stage, "non-finite acceleration of '" + b.name + "'",
             "an ill-conditioned constraint matrix (tiny masses or inertias next to large ones)");
        return false;
      }
    } else if (!finiteAndBounded(b.x) || !finite(b.q.coeffs()) || !finiteAndBounded(b.v) || !finiteAndBounded(b.w)) {
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
  // Joint by joint into rows of fixed storage: the values of ConstraintSystem::maxError() (the
  // same evaluate() and error() per joint) without building the stacked system, which allocated
  // its blocks on every call and cost as much as a step of the 1024-link chain in `sim --csv`.
  double e = 0.0;
  for (const auto& j : joints_)
    e = std::max(e, j->error(j->rowsAt(bodyOf(bodies_, j->bodyA()), bodyOf(bodies_, j->bodyB()))));
  return e;
}

double World::constraintPower() const {
  double p = 0.0;
  for (int i : dynamic_)
    p += bodies_[i].constraint_force.dot(bodies_[i].v) + bodies_[i].constraint_torque.dot(bodies_[i].w);
  return p;
}

}  // namespace ponyhop

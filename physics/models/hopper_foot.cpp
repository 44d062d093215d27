#include "physics/models/hopper_foot.h"

#include <cmath>

#include "physics/pgs.h"
#include "physics/prismatic_joint.h"
#include "physics/stabilization.h"

namespace ponyhop {

int FootContact::dimension() const {
  switch (state_->mode) {
    case ContactMode::Off:
      return 0;
    case ContactMode::Stick:
      return state_->twist ? 4 : 3;
    case ContactMode::Slide:
      return 1;
  }
  return 0;
}

// Stick rows 0-2 are the spherical joint's (physics/spherical_joint.cpp) with b = the world and
// p_b = anchor: C = R + r - anchor, J = [I  -r~], J'q' = w x (w x r), r = c - R the arm from the
// foot's centre of mass to the sphere's centre. Row 3 is the dot-product row x_f . g with g fixed
// in the world (physics/prismatic_joint.cpp): a torque about x_f x g, close to vertical.
// Slide: the normal row alone (C = n . c - level - rho; on the plane z = 0, c_z - rho).
void FootContact::evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const {
  const Eigen::Vector3d r = a.q * center_;
  const Eigen::Vector3d c = a.x + r;
  const Eigen::Vector3d wwr = a.w.cross(a.w.cross(r));
  const Eigen::Matrix3d minus_skew = -skew(r);
  switch (state_->mode) {
    case ContactMode::Off:
      return;
    case ContactMode::Stick: {
      out.C.head<3>() = c - state_->anchor;
      out.ja.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity();
      out.ja.block<3, 3>(0, 3) = minus_skew;
      out.jb.topRows<3>().setZero();
      out.bias.head<3>() = wwr;
      if (state_->twist) {
        const JointRow t = dotRow(a, a.q * Eigen::Vector3d::UnitX(), b, state_->twist_ref);
        out.C(3) = t.C;
        out.ja.row(3) = t.ja;
        out.jb.row(3).setZero();
        out.bias(3) = t.bias;
      }
      return;
    }
    case ContactMode::Slide:
      const Eigen::Vector3d& n = state_->normal;
      out.C(0) = n.dot(c) - state_->level - radius_;
      out.ja.row(0) << n.transpose(), n.transpose() * minus_skew;
      out.jb.row(0).setZero();
      out.bias(0) = n.dot(wwr);
      return;
  }
}

void KineticFriction::apply(std::vector<RigidBody>& bodies) const {
  if (state_->mode != ContactMode::Slide) return;
  RigidBody& foot = bodies[foot_];
  const Eigen::Vector3d p = foot.pointToWorld(center_) - radius_ * state_->normal;
  const Eigen::Vector3d f = -mu_ * state_->normal_force * state_->slip_dir;
  foot.force += f;
  foot.torque += (p - foot.x).cross(f);
}

GroundContact::GroundContact(World& world, int foot, const Eigen::Vector3d& center_local, double radius, double mu,
                             double twist_radius, std::shared_ptr<const Terrain> terrain)
    : foot_(foot),
      center_(center_local),
      radius_(radius),
      mu_(mu),
      twist_radius_(twist_radius),
      state_(std::make_shared<ContactState>()),
      terrain_(std::move(terrain)) {
  joint_ = world.addJoint(std::make_unique<FootContact>(foot, center_local, radius, state_));
  world.addForceElement(std::make_unique<KineticFriction>(foot, center_local, radius, mu, state_));
}

Terrain::Surface GroundContact::groundAt(const Eigen::Vector3d& c) const {
  static const Terrain kPlane;  // no boxes: the plane z = 0
  return (terrain_ ? *terrain_ : kPlane).at(c);
}

Eigen::Vector3d GroundContact::onGround(const Eigen::Vector3d& c) const {
  const Eigen::Vector3d& n = state_->normal;
  if (n == Eigen::Vector3d::UnitZ()) return Eigen::Vector3d(c.x(), c.y(), state_->level + radius_);
  return c + (state_->level + radius_ - n.dot(c)) * n;
}

namespace {

// The part of v along the ground (v minus its part along the normal).
Eigen::Vector3d tangential(const Eigen::Vector3d& v, const Eigen::Vector3d& n) {
  if (n == Eigen::Vector3d::UnitZ()) return Eigen::Vector3d(v.x(), v.y(), 0.0);
  return v - v.dot(n) * n;
}

}  // namespace

int GroundContact::rowOffset(const World& world) const {
  int row = 0;
  for (int j = 0; j < joint_; ++j) row += world.joints()[j]->dimension();
  return row;
}

// A touchdown inside the substep just taken: the toe, in flight at its start, ends it deeper than
// the tolerance. (Liftoff is not located: the ground can pull for at most the rest of one step,
// an impulse of order N' h^2 / 2; locating it by the normal force's sign costs a joint-force
// solve per substep in stance, and the bisection's mixed substep sizes set off the stability
// watch of explicit methods on the light foot's servo right after liftoff.)
bool GroundContact::impactInside(const World& world) const {
  if (!(impact_tolerance_ > 0.0) || !world.ok() || state_->mode != ContactMode::Off) return false;
  return groundAt(center(world)).distance - radius_ < -impact_tolerance_;
}

void GroundContact::update(World& world) {
  if (!world.ok()) return;
  if (state_->mode == ContactMode::Off) {
    const RigidBody& f = world.body(foot_);
    const Eigen::Vector3d c = f.pointToWorld(center_);
    const Terrain::Surface ground = groundAt(c);
    const double gap = ground.distance - radius_;
    // Touching and moving into the ground (or clearly below it): the foot lands.
    if (gap < -1e-6 || (gap <= 0.0 && ground.normal.dot(f.velocityAt(c)) <= 0.0)) touchdown(world, ground);
    return;
  }
  checkForces(world);
}

Eigen::VectorXd GroundContact::projectVelocities(World& world, bool& ok) {
  Eigen::VectorXd y;
  ok = world.projectVelocitiesOntoJoints(&y).ok();
  if (!ok || y.size() == 0) return {};
  return y.segment(rowOffset(world), world.joints()[joint_]->dimension());
}

// The toe's impulse with Coulomb friction in the same solve. The contact point's rows are its
// velocity along the normal and two tangents, u = J_c v. Through the joints (the contact's own rows
// off), a unit impulse on row k changes the velocities by W_k (the World's own mass-metric
// projection of v0 + M^-1 J_k^T, minus v0: the joints take their share), so u' = u0 + D P with
// D = J_c W. The impact is then the cone problem of the collision stage (physics/pgs.h):
// P_n >= 0 with u_n' = 0 (inelastic), |P_t| <= mu P_n, P_t opposite the slip that remains. If the
// impulse stops the slip the foot sticks (the Stick rows give the same impulse exactly);
// otherwise it slides on with that impulse, which removes kinetic energy (dK = P.u' - P^T D P / 2,
// and P_n u_n' = 0, P_t.u_t' <= 0) and cannot reverse the slip.
GroundContact::Impact GroundContact::impact(World& world, bool& ok) {
  Impact out;
  std::vector<RigidBody>& bodies = world.bodies();
  const ContactMode mode = state_->mode;
  state_->mode = ContactMode::Off;  // the joints alone
  ok = world.projectVelocitiesOntoJoints().ok();
  const std::vector<RigidBody> v0 = bodies;
  const RigidBody& f0 = v0[foot_];
  const Eigen::Vector3d& n = state_->normal;
  const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  const Eigen::Vector3d dirs[3] = {n, t1, t2};
  const Eigen::Vector3d p = f0.pointToWorld(center_) - radius_ * n;
  Eigen::Vector3d u0;
  for (int k = 0; k < 3; ++k) u0(k) = dirs[k].dot(f0.velocityAt(p));
  Eigen::Matrix3d d;
  std::vector<RigidBody> w[3];
  for (int k = 0; k < 3 && ok; ++k) {
    RigidBody& f = bodies[foot_];
    f.v += dirs[k] / f.mass;
    f.w += f.worldInverseInertia() * (p - f.x).cross(dirs[k]);
    ok = world.projectVelocitiesOntoJoints().ok();
    w[k] = bodies;
    for (int i = 0; i < 3; ++i) d(i, k) = dirs[i].dot(bodies[foot_].velocityAt(p)) - u0(i);
    for (size_t i = 0; i < bodies.size(); ++i) {
      bodies[i].v = v0[i].v;
      bodies[i].w = v0[i].w;
    }
  }
  state_->mode = mode;
  if (!ok) return out;
  d = 0.5 * (d + d.transpose()).eval();  // symmetric up to round-off
  Eigen::VectorXd impulse;
  projectedGaussSeidel(d, u0, Eigen::VectorXd::Zero(3), {{0, 3}}, {mu_}, impulse);
  // The velocities after the impulse.
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies[i].isDynamic()) continue;
    for (int k = 0; k < 3; ++k) {
      bodies[i].v += impulse(k) * (w[k][i].v - v0[i].v);
      bodies[i].w += impulse(k) * (w[k][i].w - v0[i].w);
    }
  }
  const Eigen::Vector3d u = u0 + d * Eigen::Vector3d(impulse);
  out.slip = u(1) * t1 + u(2) * t2;
  out.approach = tangential(f0.velocityAt(p), n);
  // Sticking: the slip left is round-off of the approach speed.
  out.sticks = out.slip.norm() <= 1e-9 * std::max(1.0, u0.norm());
  return out;
}

void GroundContact::touchdown(World& world, const Terrain::Surface& ground) {
  std::vector<RigidBody>& bodies = world.bodies();
  const std::vector<RigidBody> before = bodies;
  const double energy_before = world.kineticEnergy();
  const auto restoreVelocities = [&] {
    for (size_t i = 0; i < bodies.size(); ++i) {
      bodies[i].v = before[i].v;
      bodies[i].w = before[i].w;
    }
  };
  const RigidBody& f = bodies[foot_];
  const Eigen::Vector3d c = f.pointToWorld(center_);
  const Eigen::Vector3d xf = f.q * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d g = ground.normal.cross(xf);

  state_->mode = mu_ > 0.0 ? ContactMode::Stick : ContactMode::Slide;
  state_->normal = ground.normal;
  state_->level = ground.level;
  state_->anchor = onGround(c);
  state_->twist = twist_radius_ > 0.0 && mu_ > 0.0 && g.norm() > 1e-6;
  if (state_->twist) state_->twist_ref = g.normalized();
  state_->normal_force = 0.0;
  state_->friction_force.setZero();

  // No penetration is left: positions onto C = 0 (the landing point lifted to the surface).
  const ProjectionResult p = world.projectPositionsOntoJoints();
  if (!p.status.ok() || !(p.error < 1e-6)) {
    world.fail("ground contact: touchdown projection failed (" + p.status.message() + ")");
    return;
  }
  bool ok = true;
  if (state_->mode == ContactMode::Stick) {
    const Impact hit = impact(world, ok);
    if (ok && !hit.sticks) {
      // The impulse cannot stop the slip inside the friction cone: a sliding landing, with the
      // normal and friction impulse of the same solve (already applied).
      ++stats_.sliding_touchdowns;
      stats_.max_slip_reversal = std::max(stats_.max_slip_reversal, -hit.slip.dot(hit.approach.normalized()));
      state_->mode = ContactMode::Slide;
      state_->slip_dir = hit.slip.normalized();
    } else if (ok) {
      // Sticks: the Stick rows' projection (the same impulse, exact), torsion if it holds.
      restoreVelocities();
      Eigen::VectorXd y = projectVelocities(world, ok);
      const Eigen::Vector3d& n = state_->normal;
      if (ok && state_->twist && std::abs(y(3)) > mu_ * twist_radius_ * n.dot(y.head<3>())) {
        state_->twist = false;  // the landing twists the foot: torsional friction cannot hold it
        ++stats_.twist_slips;
        restoreVelocities();
        projectVelocities(world, ok);
      }
    }
  }
  // Slide (a sliding landing, or no friction): the normal row's projection (round-off of the
  // impulse above, or the frictionless impulse).
  if (ok && state_->mode == ContactMode::Slide) projectVelocities(world, ok);
  if (!ok) {
    world.fail("ground contact: touchdown velocity projection failed (singular constraint matrix)");
    return;
  }
  ++stats_.touchdowns;
  stats_.max_touchdown_energy_gain = std::max(stats_.max_touchdown_energy_gain, world.kineticEnergy() - energy_before);
  // Sliding on: the normal force (and the friction with it) at once, not a step later. A ground
  // that would have to pull right after the impulse lets the foot go again (liftoff).
  if (state_->mode == ContactMode::Slide) {
    slideForces(world);
    if (world.ok() && !(state_->normal_force > 0.0)) {
      state_->mode = ContactMode::Off;
      state_->friction_force.setZero();
    }
  }
}

// Slide: kinetic friction -mu N slip_dir acts (KineticFriction) with the normal multiplier N of
// the same solve. The joint-force solve is linear in the friction's magnitude F:
// lambda_n(F) = lambda_n(0) + s F, so two solves give the N with N = lambda_n(mu-scaled F = N)
// exactly: N = lambda_n(F0) - s F0 over (1 - s) (F0 the magnitude applied in the first solve).
// s >= 1 would be Painleve's paradox (friction pulling the foot into the ground faster than the
// normal force grows): then no consistent N exists, and the first solve's is kept (counted). A
// third solve leaves lambda() and the accelerations consistent.
void GroundContact::slideForces(World& world) {
  const int row = rowOffset(world);
  const double f0 = state_->normal_force;
  world.evaluate();
  if (!world.ok()) return;
  const double l0 = world.lambda()(row);
  const double probe = std::max(1.0, std::abs(f0));
  state_->normal_force = f0 + probe;
  world.evaluate();
  if (!world.ok()) return;
  const double s = (world.lambda()(row) - l0) / probe;
  double n = l0;
  if (s < 1.0 - 1e-9)
    n = (l0 - s * f0) / (1.0 - s);
  else
    ++stats_.inconsistent_slides;
  state_->normal_force = std::max(0.0, n);
  world.evaluate();
  if (!world.ok()) return;
  state_->friction_force = -mu_ * state_->normal_force * state_->slip_dir;
}

void GroundContact::checkForces(World& world) {
  const int row = rowOffset(world);
  if (state_->mode == ContactMode::Slide) return checkSlide(world, row);
  // Stick: the multipliers at the state just reached (with the controller's current setpoints).
  world.evaluate();
  if (!world.ok()) return;
  const Eigen::VectorXd& lambda = world.lambda();
  const Eigen::Vector3d force = lambda.segment<3>(row);
  const double n = state_->normal.dot(force);
  const Eigen::Vector3d ft = tangential(force, state_->normal);
  state_->normal_force = n;
  state_->friction_force = ft;
  state_->twist_torque = state_->twist ? lambda(row + 3) : 0.0;
  if (!(n > 0.0)) {
    state_->mode = ContactMode::Off;  // the ground would have to pull: liftoff
    state_->normal_force = 0.0;
    state_->friction_force.setZero();
    state_->twist_torque = 0.0;
    return;
  }
  if (ft.norm() > mu_ * n) {
    // The friction needed exceeds the cone: slide, opposite to the friction that held the foot,
    // with the normal force and the kinetic friction solved together from this state on.
    ++stats_.slips;
    state_->mode = ContactMode::Slide;
    state_->slip_dir = -ft.normalized();
    state_->twist_torque = 0.0;
    slideForces(world);
    return;
  }
  if (state_->twist && std::abs(state_->twist_torque) > mu_ * twist_radius_ * n) {
    ++stats_.twist_slips;
    state_->twist = false;
    state_->twist_torque = 0.0;
  }
}

void GroundContact::checkSlide(World& world, int row) {
  const RigidBody& foot = world.body(foot_);
  const Eigen::Vector3d c = foot.pointToWorld(center_);
  const Eigen::Vector3d vt = tangential(foot.velocityAt(c - radius_ * state_->normal), state_->normal);
  const bool stopped = mu_ > 0.0 && vt.dot(state_->slip_dir) <= 0.0;
  if (mu_ > 0.0 && !stopped) state_->slip_dir = vt.normalized();
  // The normal force, solved together with the kinetic friction it carries.
  if (mu_ > 0.0)
    slideForces(world);
  else
    world.evaluate();
  if (!world.ok()) return;
  const double n = world.lambda()(row);
  if (!(n > 0.0)) {
    state_->mode = ContactMode::Off;  // liftoff
    state_->normal_force = 0.0;
    state_->friction_force.setZero();
    return;
  }
  state_->normal_force = n;
  if (!stopped) return;
  // Kinetic friction has stopped the slip: stick where the foot is now.
  state_->mode = ContactMode::Stick;
  state_->anchor = onGround(c);
  state_->twist = false;
  bool ok = true;
  projectVelocities(world, ok);
  if (!ok) world.fail("ground contact: velocity projection failed when the foot stopped sliding");
}

}  // namespace ponyhop

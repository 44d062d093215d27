#include "physics/contact.h"

#include <cmath>

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

double tangentialNorm(const Eigen::Vector3d& v, const Eigen::Vector3d& n) {
  if (n == Eigen::Vector3d::UnitZ()) return std::hypot(v.x(), v.y());
  return tangential(v, n).norm();
}

}  // namespace

int GroundContact::rowOffset(const World& world) const {
  int row = 0;
  for (int j = 0; j < joint_; ++j) row += world.joints()[j]->dimension();
  return row;
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
  ok = world.projectVelocitiesOntoJoints(&y).empty();
  if (!ok || y.size() == 0) return {};
  return y.segment(rowOffset(world), world.joints()[joint_]->dimension());
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

  // No penetration is left: positions onto C = 0 (the landing point lifted to the surface).
  const ProjectionResult p = world.projectPositionsOntoJoints();
  if (!p.problem.empty() || !(p.error < 1e-6)) {
    world.fail("ground contact: touchdown projection failed (" + p.problem + ")");
    return;
  }
  bool ok = true;
  Eigen::VectorXd y = projectVelocities(world, ok);
  if (ok && state_->mode == ContactMode::Stick) {
    const Eigen::Vector3d& n = state_->normal;
    if (state_->twist && std::abs(y(3)) > mu_ * twist_radius_ * n.dot(y.head<3>())) {
      state_->twist = false;  // the landing twists the foot: torsional friction cannot hold it
      ++stats_.twist_slips;
      restoreVelocities();
      y = projectVelocities(world, ok);
    }
    if (ok && tangentialNorm(y.head<3>(), n) > mu_ * n.dot(y.head<3>())) {
      // Outside the friction cone: a sliding landing. Normal impulse alone, then Coulomb's
      // friction impulse mu P_n against the remaining slip (the joints share it out).
      ++stats_.sliding_touchdowns;
      restoreVelocities();
      state_->mode = ContactMode::Slide;
      y = projectVelocities(world, ok);
      if (ok) {
        RigidBody& foot = bodies[foot_];
        const Eigen::Vector3d cc = foot.pointToWorld(center_);
        const Eigen::Vector3d p_contact = cc - radius_ * state_->normal;
        const Eigen::Vector3d vt = tangential(foot.velocityAt(p_contact), state_->normal);
        if (vt.norm() > 1e-9) {
          state_->slip_dir = vt.normalized();
          const Eigen::Vector3d impulse = -mu_ * std::max(0.0, y(0)) * state_->slip_dir;
          foot.v += impulse / foot.mass;
          foot.w += foot.worldInverseInertia() * (p_contact - foot.x).cross(impulse);
          y = projectVelocities(world, ok);
        }
      }
    }
  }
  if (!ok) {
    world.fail("ground contact: touchdown velocity projection failed (singular constraint matrix)");
    return;
  }
  ++stats_.touchdowns;
  stats_.max_touchdown_energy_gain = std::max(stats_.max_touchdown_energy_gain, world.kineticEnergy() - energy_before);
  state_->normal_force = 0.0;
}

void GroundContact::checkForces(World& world) {
  // The multipliers at the state just reached (with the controller's current setpoints).
  world.evaluate();
  if (!world.ok()) return;
  const Eigen::VectorXd& lambda = world.lambda();
  const int row = rowOffset(world);
  if (state_->mode == ContactMode::Stick) {
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
      // The friction needed exceeds the cone: slide, opposite to the friction that held the foot.
      ++stats_.slips;
      state_->mode = ContactMode::Slide;
      state_->slip_dir = -ft.normalized();
      state_->twist_torque = 0.0;
      return;
    }
    if (state_->twist && std::abs(state_->twist_torque) > mu_ * twist_radius_ * n) {
      ++stats_.twist_slips;
      state_->twist = false;
      state_->twist_torque = 0.0;
    }
    return;
  }
  // Slide.
  const double n = lambda(row);
  state_->normal_force = std::max(0.0, n);
  state_->friction_force = -mu_ * state_->normal_force * state_->slip_dir;
  if (!(n > 0.0)) {
    state_->mode = ContactMode::Off;
    state_->normal_force = 0.0;
    state_->friction_force.setZero();
    return;
  }
  if (mu_ <= 0.0) return;
  const RigidBody& foot = world.body(foot_);
  const Eigen::Vector3d c = foot.pointToWorld(center_);
  const Eigen::Vector3d vt = tangential(foot.velocityAt(c - radius_ * state_->normal), state_->normal);
  if (vt.dot(state_->slip_dir) <= 0.0) {
    // Kinetic friction has stopped the slip: stick where the foot is now.
    state_->mode = ContactMode::Stick;
    state_->anchor = onGround(c);
    state_->twist = false;
    bool ok = true;
    projectVelocities(world, ok);
    if (!ok) world.fail("ground contact: velocity projection failed when the foot stopped sliding");
  } else {
    state_->slip_dir = vt.normalized();
  }
}

}  // namespace ponyhop

#include "physics/models/hopper.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <type_traits>

#include "physics/prismatic_joint.h"
#include "physics/soft_constraint.h"
#include "physics/spherical_joint.h"
#include "physics/validate.h"

namespace ponyhop {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

Eigen::Vector3d axisOf(const RigidBody& b, int i) { return b.q * Eigen::Vector3d::Unit(i); }

}  // namespace

Status validate(const HopperParams& p, const std::string& prefix) {
  if (Status s = checkRanges(p, prefix); !s.ok()) return s;
  if (!(p.body_mass > 0.0) || !(p.upper_mass > 0.0) || !(p.foot_mass > 0.0)) {
    return Status::error(prefix + ": body_mass, upper_mass and foot_mass must be positive");
  }
  if (!(p.body_inertia.minCoeff() > 0.0))
    return Status::error(prefix + ".body_inertia: every component must be positive");
  if (!(p.min_length < p.rest_length && p.rest_length < p.max_length)) {
    return Status::error(prefix + ": leg lengths must satisfy min_length < rest_length < max_length (got " +
                         number(p.min_length) + ", " + number(p.rest_length) + ", " + number(p.max_length) + " m)");
  }
  if (!(p.foot_length + p.toe_radius < p.min_length)) {
    return Status::error(
        prefix + ".foot_length + toe_radius = " + number(p.foot_length + p.toe_radius) +
        " m: must be less than min_length (the foot's upper end would hit the hip at full compression)");
  }
  if (!(p.max_length - p.toe_radius - p.foot_length < p.upper_length)) {
    return Status::error(prefix + ".upper_length = " + number(p.upper_length) +
                         " m: must exceed max_length - toe_radius - foot_length (the foot would leave the upper leg)");
  }
  if (p.position.z() - p.hip_offset - p.rest_length < 0.0) {
    return Status::error(prefix + ".position.z = " + number(p.position.z()) +
                         " m: the foot would start below the ground (needs >= " + number(p.hip_offset + p.rest_length) +
                         " m)");
  }
  for (size_t i = 1; i < p.script.size(); ++i) {
    if (p.script[i].t < p.script[i - 1].t) {
      return Status::error(prefix + ".script." + std::to_string(i) + ".t = " + number(p.script[i].t) +
                           " s: keys must be in time order (the previous key is at " + number(p.script[i - 1].t) +
                           " s)");
    }
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Leg length along the knee's free axis (Hecker lecture, "Access to Current State: derived state, e.g.
// scalar leg length, and its derivatives"):
//
//   z_a  the upper leg's axis (world), from the toe toward the hip
//   r    = (p_hip - c) . z_a + rho            (c the toe sphere's centre, rho its radius)
//   r'   = (v_hip - v_c) . z_a + (p_hip - c) . (w_a x z_a)
//
// p_hip is the upper leg's hip point and c lies on the axis, so r is the hip-to-ground distance
// of a vertical leg, and (by the knee's constraints) r' is the sliding speed.
LegState legState(const HopperModel& m, const std::vector<RigidBody>& bodies) {
  const RigidBody& upper = bodies[m.upper];
  const RigidBody& foot = bodies[m.foot];
  LegState s;
  s.axis = axisOf(upper, 2);
  const Eigen::Vector3d hip = upper.pointToWorld(m.hip_in_upper);
  const Eigen::Vector3d c = foot.pointToWorld(m.toe_in_foot);
  s.length = (hip - c).dot(s.axis) + m.params.toe_radius;
  s.rate = (upper.velocityAt(hip) - foot.velocityAt(c)).dot(s.axis) + (hip - c).dot(upper.w.cross(s.axis));
  return s;
}

// ComputeControllerForces (Hecker lecture): soft constraints f = k_s (C - C_d) + k_d (C' - C_d'),
// each applied along its constraint's Jacobian with equal and opposite parts on the two bodies.
//
// 1. Leg spring along the knee's free axis (C = r, C_d = r_set; Hecker lecture: "knee length: pick good
//    gains for bouncing, change leg setpoint for length control"), plus end stops at r_min and
//    r_max written with the smooth ramp (no max):
//      f = k (r_set - r) - b r'
//          + k_s ramp(r_min - r) - b_s r' step(r_min - r)      (compression stop pushes out)
//          - k_s ramp(r - r_max) - b_s r' step(r - r_max)      (extension stop pulls in)
//    f > 0 extends the leg: -f z_a on the foot, +f z_a on the upper leg, both at the foot's
//    centre of mass (on the axis, so neither gets a torque).
// 2. Hip servos, torques only (the hip is a ball joint), on the upper leg (a) and the body (b)
//    (Hecker lecture: "roll & pitch: move z_a around in b's coordinate frame using z_a . x_b and
//    z_a . y_b; yaw: x_a . y_b"). For C = s . t, C' = (w_s - w_t) . (s x t) (the dot-product
//    row of physics/prismatic_joint.cpp), so the torque is -f (s x t) on s's body and +f (s x t)
//    on t's body:
//      flight (place_weight):  C = z_a . x_b -> placement_x,  C = z_a . y_b -> placement_y,
//                              C = x_a . y_b -> 0 (leg twist follows the body)
//      stance (attitude_weight), the body against the world, the torque's reaction on the leg
//      (the ground holds the leg):  C = z_b . x_world -> 0, C = z_b . y_world -> 0 (upright),
//                              C = x_b . h_perp -> 0, h_perp = (-sin psi_d, cos psi_d, 0) (heading)
//    The weights are setpoints (0 or 1, set by Think), not branches in the force law.
void computeHopperForces(const HopperModel& m, const HopperSetpoints& s, double /*t*/, std::vector<RigidBody>& bodies) {
  const HopperParams& p = m.params;
  RigidBody& body = bodies[m.body];
  RigidBody& upper = bodies[m.upper];
  RigidBody& foot = bodies[m.foot];

  // 1. Leg spring and stops.
  const LegState leg = legState(m, bodies);
  const double r = leg.length, rd = leg.rate, eps = p.stop_smoothing;
  const double f =
      p.leg_stiffness * (s.leg_length - r) - p.leg_damping * rd + p.stop_stiffness * smoothRamp(p.min_length - r, eps) -
      p.stop_damping * rd * smoothStep(p.min_length - r, eps) - p.stop_stiffness * smoothRamp(r - p.max_length, eps) -
      p.stop_damping * rd * smoothStep(r - p.max_length, eps);
  foot.force -= f * leg.axis;
  upper.force += f * leg.axis;

  // 2. Hip servos.
  const Eigen::Vector3d xa = axisOf(upper, 0), za = leg.axis;
  const Eigen::Vector3d xb = axisOf(body, 0), yb = axisOf(body, 1), zb = axisOf(body, 2);
  const Eigen::Vector3d dw = upper.w - body.w;
  Eigen::Vector3d torque_leg = Eigen::Vector3d::Zero();  // on the upper leg; the body gets -torque_leg
  const auto relative = [&](const Eigen::Vector3d& sa, const Eigen::Vector3d& tb, double ks, double kd,
                            double cd) -> Eigen::Vector3d {
    const Eigen::Vector3d n = sa.cross(tb);
    return softConstraintForce(ks, kd, sa.dot(tb), cd, dw.dot(n)) * n;  // f (s x t)
  };
  torque_leg -= s.place_weight * relative(za, xb, p.placement_stiffness, p.placement_damping, s.placement_x);
  torque_leg -= s.place_weight * relative(za, yb, p.placement_stiffness, p.placement_damping, s.placement_y);
  torque_leg -= s.place_weight * relative(xa, yb, p.twist_stiffness, p.twist_damping, 0.0);

  Eigen::Vector3d torque_body = Eigen::Vector3d::Zero();  // on the body; the leg gets -torque_body
  const auto absolute = [&](const Eigen::Vector3d& sb, const Eigen::Vector3d& t_world, double ks,
                            double kd) -> Eigen::Vector3d {
    const Eigen::Vector3d n = sb.cross(t_world);
    return softConstraintForce(ks, kd, sb.dot(t_world), 0.0, body.w.dot(n)) * n;
  };
  const Eigen::Vector3d h_perp(-std::sin(s.heading), std::cos(s.heading), 0.0);
  torque_body -= s.attitude_weight * absolute(zb, Eigen::Vector3d::UnitX(), p.attitude_stiffness, p.attitude_damping);
  torque_body -= s.attitude_weight * absolute(zb, Eigen::Vector3d::UnitY(), p.attitude_stiffness, p.attitude_damping);
  torque_body -= s.attitude_weight * absolute(xb, h_perp, p.yaw_stiffness, p.yaw_damping);
  // The leg takes the reaction; only the toe's torsional friction holds it about its own axis, so
  // that component is held within yaw_torque_limit (the rest goes through the hip and the toe).
  const double axial = torque_body.dot(za);
  if (std::abs(axial) > s.yaw_torque_limit) torque_body -= (axial - std::copysign(s.yaw_torque_limit, axial)) * za;

  upper.torque += torque_leg - torque_body;
  body.torque += torque_body - torque_leg;
}

// ---------------------------------------------------------------------------------------------

std::shared_ptr<Hopper> Hopper::add(World& world, const HopperParams& params, std::shared_ptr<const Terrain> terrain) {
  auto h = std::make_shared<Hopper>(Key{}, world, params, std::move(terrain));
  if (h->built()) {
    world.addController(h);
    world.addContactSet(h->contact_);
  }
  return h;
}

Hopper::Hopper(Key, World& world, const HopperParams& params, std::shared_ptr<const Terrain> terrain)
    : params_(params) {
  mem_.command = params.command;
  if (Status s = validate(params); !s.ok()) {
    world.fail(s.message());
    return;
  }
  const HopperParams& p = params_;
  HopperModel& m = model_;
  m.params = p;
  mem_.stance_time = p.stance_time;
  // The heading setpoint starts at the body's own yaw (0: every frame starts aligned with the
  // world) and slews toward the command: starting at a commanded 90 deg would leave the yaw servo
  // on its equilibrium at 90 deg from the setpoint, and the body would never turn.
  mem_.heading = 0.0;
  mem_.desired_velocity = p.velocity.head<2>();  // the command is approached from the initial motion

  // Body: hip below its centre of mass. Upper leg: a tube (solid-cylinder inertia) from the hip
  // down, centre of mass halfway. Foot: a rod, the toe sphere's centre at its lower end, centre
  // of mass halfway. All frames start aligned with the world, the leg vertical at rest length.
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d hip = p.position - p.hip_offset * ez;
  RigidBody body;
  body.name = "hopper body";
  body.mass = p.body_mass;
  body.inertia = p.body_inertia;
  body.x = p.position;
  body.v = p.velocity;
  m.body = world.addDynamicBody(body);

  const auto rod = [](double mass, double length, double radius) {
    const double across = mass * (3.0 * radius * radius + length * length) / 12.0;
    return Eigen::Vector3d(across, across, 0.5 * mass * radius * radius);
  };
  RigidBody upper;
  upper.name = "hopper upper leg";
  upper.mass = p.upper_mass;
  upper.inertia = rod(p.upper_mass, p.upper_length, p.upper_radius);
  upper.x = hip - 0.5 * p.upper_length * ez;
  upper.v = p.velocity;
  m.upper = world.addDynamicBody(upper);

  RigidBody foot;
  foot.name = "hopper foot";
  foot.mass = p.foot_mass;
  foot.inertia = rod(p.foot_mass, p.foot_length, p.foot_radius);
  const Eigen::Vector3d toe = hip - (p.rest_length - p.toe_radius) * ez;
  foot.x = toe + 0.5 * p.foot_length * ez;
  foot.v = p.velocity;
  m.foot = world.addDynamicBody(foot);

  m.hip_in_body = -p.hip_offset * ez;
  m.hip_in_upper = 0.5 * p.upper_length * ez;
  m.toe_in_foot = -0.5 * p.foot_length * ez;
  m.hip_joint = world.addJoint(std::make_unique<SphericalJoint>(m.body, m.hip_in_body, m.upper, m.hip_in_upper));
  m.knee_joint =
      world.addJoint(std::make_unique<PrismaticJoint>(m.upper, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(),
                                                      m.foot, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()));
  contact_ = std::make_shared<GroundContact>(world, m.foot, m.toe_in_foot, p.toe_radius, p.friction, p.twist_radius,
                                             std::move(terrain));
  contact_->locateEvents(p.impact_tolerance);

  mem_.setpoints.leg_length = p.rest_length;
  mem_.setpoints.heading = mem_.heading;
}

void Hopper::applyForces(World& world, double t) { computeHopperForces(model_, mem_.setpoints, t, world.bodies()); }

void Hopper::restoreState(const std::any& s) {
  mem_ = std::any_cast<const Memory&>(s);
  params_.command = mem_.command;
}

Status Hopper::setCommand(const HopperCommand& command) {
  if (Status s = checkRanges(command, "hopper.command"); !s.ok()) return s;
  params_.command = command;
  mem_.command = command;
  return {};
}

HopperCommand Hopper::commandAt(double t) const { return courseCommandAt(params_.script, t, mem_.command); }

double Hopper::mass() const { return params_.body_mass + params_.upper_mass + params_.foot_mass; }

Eigen::Vector3d Hopper::centerOfMass(const World& world) const {
  const HopperModel& m = model_;
  const RigidBody &b = world.body(m.body), &u = world.body(m.upper), &f = world.body(m.foot);
  return (b.mass * b.x + u.mass * u.x + f.mass * f.x) / (b.mass + u.mass + f.mass);
}

Eigen::Vector3d Hopper::centerOfMassVelocity(const World& world) const {
  const HopperModel& m = model_;
  const RigidBody &b = world.body(m.body), &u = world.body(m.upper), &f = world.body(m.foot);
  return (b.mass * b.v + u.mass * u.v + f.mass * f.v) / (b.mass + u.mass + f.mass);
}

// Think (Hecker lecture): the state machine over the hop; it changes setpoints only.
//
//   FLIGHT      -> LOADING      touchdown (the contact became active)
//   LOADING     -> COMPRESSION  r < rest_length - load_depth
//   COMPRESSION -> THRUST       r' >= 0 (the leg stops shortening: bottom of the stance)
//   THRUST      -> UNLOADING    r > r_set - unload_margin (the spring is nearly spent)
//   any stance  -> FLIGHT       liftoff (the contact released: the ground would have to pull)
//
// Setpoints per phase (Raibert's three parts):
//   FLIGHT       leg at rest length (shortened by flight_retract while rising); after swing_delay
//                (the foot clears the ground) the hip servo places
//                the leg for the touchdown: foot at x_f = xdot T_s / 2 + k_xdot (xdot - xdot_d)
//                from the centre of mass, both horizontal axes, T_s the last measured stance,
//                plus a small per-hop integral of the speed error (speed_integral_gain).
//   LOADING      leg at rest length; hip torque off (the foot is barely loaded and would slip).
//   COMPRESSION  leg at rest length; hip servos the body upright and to the heading.
//   THRUST       leg setpoint r0 + delta: hop height (delta from the energy still needed to
//                reach the commanded apex, plus a per-hop trim from the apex error); attitude on.
//   UNLOADING    thrust held; hip torque off.
void Hopper::think(World& world) {
  if (!built() || !world.ok()) return;
  const double now = world.time();
  const double dt = mem_.last_time < 0.0 ? 0.0 : now - mem_.last_time;
  mem_.last_time = now;
  const HopperParams& p = params_;
  const HopperCommand cmd = commandAt(now);
  const RigidBody& body = world.body(model_.body);
  const LegState leg = this->leg(world);
  const bool contact = contact_->inContact();
  const double g = std::max(1e-9, -world.params().gravity.z());

  const auto liftoff = [&] {
    mem_.phase = HopperPhase::Flight;
    mem_.stance_time = std::clamp(now - mem_.touchdown_time, 0.05, 1.0);
    mem_.liftoff_time = now;
    mem_.liftoff_length = leg.length;
    // The leg's direction in the body frame at liftoff: the swing starts from here.
    mem_.liftoff_placement = Eigen::Vector2d(leg.axis.dot(axisOf(body, 0)), leg.axis.dot(axisOf(body, 1)));
    mem_.flight_max_z = body.x.z();
    ++mem_.hops;
  };
  switch (mem_.phase) {
    case HopperPhase::Flight:
      mem_.flight_max_z = std::max(mem_.flight_max_z, body.x.z());
      if (contact) {
        mem_.phase = HopperPhase::Loading;
        mem_.touchdown_time = now;
        if (mem_.touchdowns > 0) {
          mem_.last_apex = mem_.flight_max_z;
          // Per-hop trim of the thrust from the apex error (integral action on the losses the
          // energy estimate below does not know: damping, the foot's impact, a ponytail).
          mem_.height_trim =
              std::clamp(mem_.height_trim + p.height_gain * (cmd.height - (mem_.last_apex - mem_.stance_ground)),
                         -p.thrust_max, p.thrust_max);
        }
        // Per-hop integral of the speed error on the foot placement (the neutral point
        // x' T_s / 2 is only approximately where the hopper neither speeds up nor slows down).
        const Eigen::Vector3d v = centerOfMassVelocity(world);
        const double trim_limit = 0.25 * p.rest_length * std::sin(p.max_leg_angle * kDeg);
        mem_.speed_trim += p.speed_integral_gain * (v.head<2>() - mem_.desired_velocity);
        if (mem_.speed_trim.norm() > trim_limit) mem_.speed_trim *= trim_limit / mem_.speed_trim.norm();
        ++mem_.touchdowns;
      }
      break;
    case HopperPhase::Loading:
      if (!contact) {
        liftoff();
      } else if (leg.length < p.rest_length - p.load_depth) {
        mem_.phase = HopperPhase::Compression;
      }
      break;
    case HopperPhase::Compression:
      if (!contact) {
        liftoff();
      } else if (leg.rate >= 0.0) {
        mem_.phase = HopperPhase::Thrust;
        // Energy to reach the commanded apex from here (vertical part): the spring, extended to
        // r0 + delta, must release 1/2 k (r0 + delta - r)^2 = M g (h_d - z) - 1/2 M z'^2.
        const double m_total = mass();
        mem_.stance_ground = contact_->groundHeight(world);
        const double needed = std::max(0.0, m_total * g * (cmd.height + mem_.stance_ground - body.x.z()) -
                                                0.5 * m_total * body.v.z() * body.v.z());
        const double feedforward = std::sqrt(2.0 * needed / p.leg_stiffness) - (p.rest_length - leg.length);
        mem_.thrust = std::clamp(feedforward + mem_.height_trim, -0.5 * (p.rest_length - p.min_length), p.thrust_max);
      }
      break;
    case HopperPhase::Thrust:
      if (!contact) {
        liftoff();
      } else if (leg.length > p.rest_length + mem_.thrust - p.unload_margin) {
        mem_.phase = HopperPhase::Unloading;
      }
      break;
    case HopperPhase::Unloading:
      if (!contact) liftoff();
      break;
  }
  updateSetpoints(world, cmd, dt);
}

void Hopper::updateSetpoints(const World& world, const HopperCommand& cmd, double dt) {
  const HopperParams& p = params_;
  const double now = world.time();
  HopperSetpoints& s = mem_.setpoints;
  const RigidBody& body = world.body(model_.body);

  // Heading setpoint slews toward the command (a step of 180 degrees would sit on the servo's
  // unstable equilibrium).
  const double target = cmd.heading * kDeg;
  const double step = p.max_yaw_rate * kDeg * dt;
  mem_.heading += std::clamp(std::remainder(target - mem_.heading, 2.0 * std::numbers::pi), -step, step);
  s.heading = mem_.heading;
  // Desired velocity slews toward the command at max_acceleration (a step in speed asks for
  // one big foot placement error at once).
  const Eigen::Vector2d v_cmd(cmd.vx, cmd.vy);
  const Eigen::Vector2d dv = v_cmd - mem_.desired_velocity;
  const double max_dv = p.max_acceleration * dt;
  mem_.desired_velocity += dv.norm() > max_dv ? Eigen::Vector2d(dv * (max_dv / dv.norm())) : dv;

  switch (mem_.phase) {
    case HopperPhase::Flight: {
      // Rising: the leg is pulled in below its liftoff length (the foot, resting on the ground
      // when the normal force reached zero, must be lifted, not pushed back down).
      s.leg_length = body.v.z() > 0.0 ? std::min(p.rest_length, mem_.liftoff_length) - p.flight_retract : p.rest_length;
      s.place_weight = 1.0;
      s.attitude_weight = 0.0;
      // Foot placement (Raibert): neutral point plus the speed correction, both axes.
      const Eigen::Vector3d v = centerOfMassVelocity(world);
      Eigen::Vector2d xf =
          v.head<2>() * mem_.stance_time / 2.0 + p.speed_gain * (v.head<2>() - mem_.desired_velocity) + mem_.speed_trim;
      // x_f is measured from the centre of mass; the leg pivots at the hip, which a pitched or
      // rolled body carries off to the side (hip_offset sin(tilt)).
      const Eigen::Vector3d hip = body.pointToWorld(model_.hip_in_body);
      xf += centerOfMass(world).head<2>() - hip.head<2>();
      const double limit = p.rest_length * std::sin(p.max_leg_angle * kDeg);
      if (xf.norm() > limit) xf *= limit / xf.norm();
      // Desired leg axis (from the foot up to the hip) in the world, then in the body's frame.
      const Eigen::Vector3d za_d =
          Eigen::Vector3d(-xf.x(), -xf.y(), std::sqrt(p.rest_length * p.rest_length - xf.squaredNorm())) /
          p.rest_length;
      // The swing waits swing_delay after liftoff (the retracting foot clears the ground first;
      // a leg swung forward at once sweeps its foot into the ground), then blends in over
      // swing_delay more.
      const double blend = mem_.hops == 0 ? 1.0 : std::clamp((now - mem_.liftoff_time) / p.swing_delay - 1.0, 0.0, 1.0);
      s.placement_x = (1.0 - blend) * mem_.liftoff_placement.x() + blend * za_d.dot(axisOf(body, 0));
      s.placement_y = (1.0 - blend) * mem_.liftoff_placement.y() + blend * za_d.dot(axisOf(body, 1));
      break;
    }
    case HopperPhase::Loading:
      s.leg_length = p.rest_length;
      s.place_weight = 0.0;
      s.attitude_weight = 0.0;
      break;
    case HopperPhase::Compression:
      s.leg_length = p.rest_length;
      s.place_weight = 0.0;
      s.attitude_weight = 1.0;
      break;
    case HopperPhase::Thrust:
      s.leg_length = p.rest_length + mem_.thrust;
      s.place_weight = 0.0;
      s.attitude_weight = 1.0;
      break;
    case HopperPhase::Unloading:
      s.leg_length = p.rest_length + mem_.thrust;
      s.place_weight = 0.0;
      s.attitude_weight = 0.0;
      break;
  }
  // The heading servo asks no more than the toe can hold (90 % of the torsional friction at the
  // last normal force; none once the torsion row has slipped this stance).
  const ContactState& cs = contact_->state();
  s.yaw_torque_limit = !contact_->inContact() ? std::numeric_limits<double>::infinity()
                       : cs.twist             ? 0.9 * p.friction * std::max(cs.normal_force, 0.0) * p.twist_radius
                                              : 0.0;
}

Eigen::Vector3d Hopper::attitude(const World& world) const {
  const Eigen::Matrix3d r = world.body(model_.body).rotation();
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  return {roll, pitch, yaw};
}

double Hopper::tilt(const World& world) const {
  const Eigen::Vector3d zb = axisOf(world.body(model_.body), 2);
  return std::acos(std::clamp(zb.z(), -1.0, 1.0));
}

namespace {
double jointError(const World& world, int joint) {
  const Constraint& c = *world.joints()[joint];
  const auto bodyOf = [&](int i) -> const RigidBody& { return i == kWorldBody ? worldBody() : world.body(i); };
  const ConstraintRows rows = c.rowsAt(bodyOf(c.bodyA()), bodyOf(c.bodyB()));
  return rows.C.size() ? rows.C.cwiseAbs().maxCoeff() : 0.0;
}
}  // namespace

double Hopper::kneeError(const World& world) const { return jointError(world, model_.knee_joint); }
double Hopper::hipError(const World& world) const { return jointError(world, model_.hip_joint); }

HopperShape Hopper::shape(const World& world) const {
  const HopperModel& m = model_;
  const RigidBody &b = world.body(m.body), &u = world.body(m.upper), &f = world.body(m.foot);
  HopperShape s;
  s.body_x = b.x;
  s.body_q = b.q;
  s.hip = u.pointToWorld(m.hip_in_upper);
  s.upper_bottom = u.pointToWorld(-m.hip_in_upper);
  s.toe = f.pointToWorld(m.toe_in_foot);
  s.foot_top = f.pointToWorld(-m.toe_in_foot);
  return s;
}

Eigen::Vector3d Hopper::backPoint() const {
  return Eigen::Vector3d(-0.5 * params_.body_size.x(), 0.0, 0.1 * params_.body_size.z());
}

}  // namespace ponyhop

// The Raibert hopper's parameters (plain data, defaults in the spirit of Raibert's machines:
// a 10 kg body, a 1 kg leg of 0.8 m, a leg spring that gives about 0.2 s of stance) and its
// commands. The state machine, the controller and the contact live in physics/models/hopper.h.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "physics/reflect.h"

namespace ponyhop {

// The phases of a hop (Raibert; thresholds in HopperParams and docs/HOPPER.md).
enum class HopperPhase { Flight, Loading, Compression, Thrust, Unloading };
template <>
struct EnumNames<HopperPhase> {
  static constexpr std::array<std::string_view, 5> names{"flight", "loading", "compression", "thrust", "unloading"};
};

// What the hopper is asked to do.
struct HopperCommand {
  double vx = 0.0;       // m/s, desired horizontal velocity along world x
  double vy = 0.0;       // m/s, desired horizontal velocity along world y
  double height = 1.05;  // m, desired apex height of the body's centre of mass
  double heading = 0.0;  // deg, desired yaw of the body (from +x toward +y)

  template <class V>
  void reflect(V& v) {
    v("vx", vx, {.unit = "m/s", .min = -5, .max = 5, .help = "Desired horizontal velocity along x"});
    v("vy", vy, {.unit = "m/s", .min = -5, .max = 5, .help = "Desired horizontal velocity along y"});
    v("height", height, {.unit = "m", .min = 0.5, .max = 3, .help = "Desired apex height of the body's centre"});
    v("heading", heading, {.unit = "deg", .min = -720, .max = 720, .help = "Desired body yaw (from +x toward +y)"});
  }
};

// One entry of a scripted course: from time t on, the command is (vx, vy, height, heading).
struct HopperCommandKey {
  double t = 0.0;  // s
  double vx = 0.0;
  double vy = 0.0;
  double height = 1.05;
  double heading = 0.0;

  template <class V>
  void reflect(V& v) {
    v("t", t, {.unit = "s", .min = 0, .max = 1e6, .help = "Time from which this command holds"});
    v("vx", vx, {.unit = "m/s", .min = -5, .max = 5, .help = "Desired velocity along x"});
    v("vy", vy, {.unit = "m/s", .min = -5, .max = 5, .help = "Desired velocity along y"});
    v("height", height, {.unit = "m", .min = 0.5, .max = 3, .help = "Desired apex height of the body's centre"});
    v("heading", heading, {.unit = "deg", .min = -720, .max = 720, .help = "Desired body yaw"});
  }
};

// The command of a course at time t: its last key with key.t <= t, else `before` (the course has
// no key yet).
inline HopperCommand courseCommandAt(const std::vector<HopperCommandKey>& course, double t,
                                     const HopperCommand& before) {
  HopperCommand c = before;
  for (const HopperCommandKey& k : course) {
    if (k.t > t + 1e-12) break;
    c = HopperCommand{k.vx, k.vy, k.height, k.heading};
  }
  return c;
}

struct HopperParams {
  // Body: a massive box-like body; the hip sits below its centre of mass.
  double body_mass = 10.0;                      // kg
  Eigen::Vector3d body_inertia{0.6, 0.6, 0.8};  // kg m^2, principal, body frame (x forward, z up)
  Eigen::Vector3d body_size{0.56, 0.34, 0.2};   // m, drawn size (x, y, z)
  double hip_offset = 0.12;                     // m, hip below the body's centre of mass

  // Leg: an upper leg (tube) hanging from the hip, a foot (rod + toe sphere) sliding in it.
  double upper_mass = 0.7;      // kg
  double upper_length = 0.45;   // m, hip to the tube's lower end (its centre of mass halfway)
  double upper_radius = 0.035;  // m
  double foot_mass = 0.3;       // kg
  double foot_length = 0.45;    // m, toe sphere centre to the rod's upper end (centre of mass halfway)
  double foot_radius = 0.016;   // m, rod
  double toe_radius = 0.03;     // m, the toe sphere that touches the ground
  double rest_length = 0.8;     // m, leg length (hip to toe along the leg) where the spring is at rest
  double min_length = 0.55;     // m, compression stop
  double max_length = 0.92;     // m, extension stop

  // Leg spring (soft constraint along the knee's free axis): f = k (r_set - r) - b r' + stops.
  double leg_stiffness = 2500.0;  // N/m
  double leg_damping = 10.0;      // N s/m
  double stop_stiffness = 2e4;    // N/m, both ends of travel
  double stop_damping = 100.0;    // N s/m
  double stop_smoothing = 0.001;  // m, width over which a stop engages (smooth force law)
  double thrust_max = 0.12;       // m, largest setpoint extension during thrust
  double flight_retract = 0.03;   // m, leg shortened while rising (foot clearance)

  // Hip servos (soft constraints between leg and body, torques equal and opposite).
  double placement_stiffness = 120.0;  // N m, leg direction in the body frame (flight)
  double placement_damping = 8.0;      // N m s
  double twist_stiffness = 0.5;        // N m, leg twist to the body's (flight)
  double twist_damping = 0.01;         // N m s
  double attitude_stiffness = 90.0;    // N m, body roll and pitch (stance)
  double attitude_damping = 12.0;      // N m s
  double yaw_stiffness = 20.0;         // N m, body heading (stance)
  double yaw_damping = 4.0;            // N m s
  double max_yaw_rate = 60.0;          // deg/s, heading setpoint slew rate

  // Controller (Raibert's three parts; thresholds of the state machine).
  double speed_gain = 0.08;           // s, k_xdot in x_f = xdot T_s / 2 + k_xdot (xdot - xdot_d)
  double max_acceleration = 0.5;      // m/s^2, desired velocity slews toward the command this fast
  double speed_integral_gain = 0.02;  // s, per-hop integral of the speed error on x_f
  double stance_time = 0.2;           // s, T_s before the first stance is measured
  double max_leg_angle = 25.0;        // deg, largest foot placement angle from vertical
  double swing_delay = 0.04;          // s, after liftoff before the leg swings (then as long to blend in)
  double height_gain = 0.3;           // m/m, thrust correction per metre of apex error (per hop)
  double load_depth = 0.02;           // m, LOADING -> COMPRESSION when r < rest_length - load_depth
  double unload_margin = 0.02;        // m, THRUST -> UNLOADING when r > r_set - unload_margin

  // Ground contact (plane z = 0).
  double friction = 1.0;       // Coulomb mu
  double twist_radius = 0.02;  // m, torsional friction limit = mu * normal force * twist_radius
  // m, touchdowns are located within the step to this depth (physics/models/hopper_foot.h); 0: at the end
  // of the step in which they happen
  double impact_tolerance = 1e-4;

  // Initial state and commands.
  Eigen::Vector3d position{0.0, 0.0, 1.05};  // m, body centre of mass at t = 0 (leg vertical, at rest length)
  Eigen::Vector3d velocity{0.0, 0.0, 0.0};   // m/s at t = 0
  HopperCommand command;                     // used when no script key applies
  std::vector<HopperCommandKey> script;      // a course: each key holds from its t on

  template <class V>
  void reflect(V& v) {
    v("body_mass", body_mass, {.unit = "kg", .min = 0.01, .max = 1e4, .help = "Mass of the body", .log = true});
    v("body_inertia", body_inertia,
      {.unit = "kg m^2", .min = 1e-5, .max = 1e4, .help = "Principal inertia of the body (x fwd, z up)"});
    v("body_size", body_size,
      {.unit = "m",
       .min = 0.01,
       .max = 10,
       .help = "Size of the body (x fwd, z up): drawn, and where a ponytail hangs"});
    v("hip_offset", hip_offset, {.unit = "m", .min = 0, .max = 5, .help = "Hip below the body's centre of mass"});
    v("upper_mass", upper_mass, {.unit = "kg", .min = 1e-3, .max = 1e3, .help = "Mass of the upper leg", .log = true});
    v("upper_length", upper_length, {.unit = "m", .min = 0.01, .max = 10, .help = "Length of the upper leg"});
    v("upper_radius", upper_radius, {.unit = "m", .min = 1e-3, .max = 1, .help = "Radius of the upper leg"});
    v("foot_mass", foot_mass, {.unit = "kg", .min = 1e-3, .max = 1e3, .help = "Mass of the foot", .log = true});
    v("foot_length", foot_length, {.unit = "m", .min = 0.01, .max = 10, .help = "Length of the foot rod"});
    v("foot_radius", foot_radius, {.unit = "m", .min = 1e-3, .max = 1, .help = "Radius of the foot rod"});
    v("toe_radius", toe_radius, {.unit = "m", .min = 1e-3, .max = 1, .help = "Radius of the toe sphere"});
    v("rest_length", rest_length, {.unit = "m", .min = 0.05, .max = 10, .help = "Leg length at spring rest"});
    v("min_length", min_length, {.unit = "m", .min = 0.05, .max = 10, .help = "Leg length at the compression stop"});
    v("max_length", max_length, {.unit = "m", .min = 0.05, .max = 10, .help = "Leg length at the extension stop"});
    v("leg_stiffness", leg_stiffness, {.unit = "N/m", .min = 1, .max = 1e6, .help = "Leg spring", .log = true});
    v("leg_damping", leg_damping, {.unit = "N s/m", .min = 0, .max = 1e4, .help = "Leg spring damping"});
    v("stop_stiffness", stop_stiffness, {.unit = "N/m", .min = 1, .max = 1e7, .help = "End stops", .log = true});
    v("stop_damping", stop_damping, {.unit = "N s/m", .min = 0, .max = 1e5, .help = "End stop damping"});
    v("stop_smoothing", stop_smoothing,
      {.unit = "m", .min = 1e-6, .max = 0.1, .help = "Stop engagement width", .log = true});
    v("thrust_max", thrust_max, {.unit = "m", .min = 0, .max = 1, .help = "Largest thrust setpoint extension"});
    v("flight_retract", flight_retract, {.unit = "m", .min = 0, .max = 1, .help = "Leg shortening while rising"});
    v("placement_stiffness", placement_stiffness,
      {.unit = "N m", .min = 0, .max = 1e5, .help = "Hip servo: leg direction (flight)"});
    v("placement_damping", placement_damping,
      {.unit = "N m s", .min = 0, .max = 1e4, .help = "Hip servo damping (flight)"});
    v("twist_stiffness", twist_stiffness,
      {.unit = "N m", .min = 0, .max = 1e4, .help = "Hip servo: leg twist (flight)"});
    v("twist_damping", twist_damping, {.unit = "N m s", .min = 0, .max = 1e3, .help = "Leg twist damping (flight)"});
    v("attitude_stiffness", attitude_stiffness,
      {.unit = "N m", .min = 0, .max = 1e5, .help = "Hip servo: body roll/pitch (stance)"});
    v("attitude_damping", attitude_damping,
      {.unit = "N m s", .min = 0, .max = 1e4, .help = "Body roll/pitch damping (stance)"});
    v("yaw_stiffness", yaw_stiffness,
      {.unit = "N m", .min = 0, .max = 1e5, .help = "Hip servo: body heading (stance)"});
    v("yaw_damping", yaw_damping, {.unit = "N m s", .min = 0, .max = 1e4, .help = "Body heading damping (stance)"});
    v("max_yaw_rate", max_yaw_rate, {.unit = "deg/s", .min = 1, .max = 3600, .help = "Heading setpoint slew rate"});
    v("speed_gain", speed_gain, {.unit = "s", .min = 0, .max = 1, .help = "k_xdot of foot placement"});
    v("max_acceleration", max_acceleration,
      {.unit = "m/s^2", .min = 0.01, .max = 100, .help = "Slew rate of the desired velocity"});
    v("speed_integral_gain", speed_integral_gain,
      {.unit = "s", .min = 0, .max = 1, .help = "Per-hop integral of the speed error on foot placement"});
    v("stance_time", stance_time, {.unit = "s", .min = 0.01, .max = 2, .help = "Stance time before one is measured"});
    v("max_leg_angle", max_leg_angle,
      {.unit = "deg", .min = 0, .max = 60, .help = "Largest placement angle from vertical"});
    v("swing_delay", swing_delay,
      {.unit = "s", .min = 1e-3, .max = 1, .help = "Wait after liftoff before the leg swings"});
    v("height_gain", height_gain, {.min = 0, .max = 5, .help = "Thrust correction per metre of apex error"});
    v("load_depth", load_depth, {.unit = "m", .min = 0, .max = 1, .help = "LOADING ends at this compression"});
    v("unload_margin", unload_margin,
      {.unit = "m", .min = 0, .max = 1, .help = "THRUST ends this short of the setpoint"});
    v("friction", friction, {.min = 0, .max = 10, .help = "Coulomb friction coefficient of the foot"});
    v("twist_radius", twist_radius, {.unit = "m", .min = 0, .max = 1, .help = "Torsional friction radius of the foot"});
    v("impact_tolerance", impact_tolerance,
      {.unit = "m",
       .min = 0,
       .max = 1,
       .help = "Touchdowns are located within the step to this depth (0: at the end of the step)"});
    v("position", position,
      {.unit = "m", .min = -1e4, .max = 1e4, .help = "Body centre of mass at t = 0", .apply = Apply::Restart});
    v("velocity", velocity,
      {.unit = "m/s", .min = -100, .max = 100, .help = "Body velocity at t = 0", .apply = Apply::Restart});
    v("command", command, {.help = "Command when no script key applies"});
    v("script", script, {.help = "Scripted course: commands from time t on", .apply = Apply::Restart});
  }
};

}  // namespace ponyhop

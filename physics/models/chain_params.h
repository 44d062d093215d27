// A chain of rigid links joined by spherical joints: the ponytail, and the canonical chain
// that other engines are compared on (assets/scenes/chain.json).
#pragma once

#include <Eigen/Core>

#include "physics/reflect.h"

namespace ponyhop {

// What the chain's first joint is attached to.
enum class ChainAttach { Anchor, Head, Hopper };
template <>
struct EnumNames<ChainAttach> {
  static constexpr std::array<std::string_view, 3> names{"anchor", "head", "hopper"};
};

// A servo on a chain's root hinge (physics/hinge_joint.h, HingeServo): a PD soft constraint that
// turns the first link about chain.hinge at `speed` from its pose at t = 0. Off when both gains
// are 0 (the default).
struct ServoParams {
  double speed = 0.0;      // rad/s, the target angle's rate
  double stiffness = 0.0;  // N m/rad
  double damping = 0.0;    // N m s/rad

  template <class V>
  void reflect(V& v) {
    v("speed", speed, {.unit = "rad/s", .min = -1e3, .max = 1e3, .help = "Rate the servo turns the root hinge at"});
    v("stiffness", stiffness,
      {.unit = "N m/rad", .min = 0, .max = 1e6, .help = "Servo stiffness on the hinge angle (0 and damping 0: off)"});
    v("damping", damping,
      {.unit = "N m s/rad", .min = 0, .max = 1e4, .help = "Servo damping on the hinge rate (0 and stiffness 0: off)"});
  }
};

// Defaults are the canonical chain: identical solid cylinders, no damping, no stiffness, no drag.
struct ChainParams {
  int links = 8;           // count
  double length = 0.05;    // m, each link
  double mass = 0.02;      // kg, the first link; tapered links scale with their volume
  double radius = 0.01;    // m, the first link's radius
  double taper = 1.0;      // tip radius / root radius (1: cylinders)
  double damping = 0.0;    // N m s/rad, at the root joint, on the relative angular velocity
  double stiffness = 0.0;  // N m/rad, at the root joint, bending toward the rest pose
  // Root-to-tip curves: the last joint's value over the first's; the joints between follow a
  // geometric curve (joint i of n: ratio^(i/(n-1))). 1: the same at every joint.
  double stiffness_tip = 1.0;
  double damping_tip = 1.0;
  double drag = 0.0;                         // N s/m per metre of link, linear air drag on each link
  Eigen::Vector3d direction{1.0, 0.0, 0.0};  // initial direction from the anchor (unit)
  ChainAttach attach = ChainAttach::Anchor;
  // The first joint as a hinge about this axis (world, at t = 0) instead of a spherical joint; 0 0 0:
  // spherical. The four-bar's crank (assets/scenes/four_bar.json).
  Eigen::Vector3d hinge{0.0, 0.0, 0.0};
  ServoParams servo;  // drives the root hinge

  template <class V>
  void reflect(V& v) {
    // Slider to 128: the dense solver is O(n^3), beyond ~100 links a step takes long (typed: 4096).
    v("links", links,
      {.min = 1,
       .max = 4096,
       .help = "Number of links",
       .log = true,
       .apply = Apply::Restart,
       .soft_min = 1,
       .soft_max = 128});
    v("length", length,
      {.unit = "m", .min = 1e-4, .max = 10, .help = "Length of each link", .log = true, .apply = Apply::Restart});
    v("mass", mass, {.unit = "kg", .min = 1e-6, .max = 1e4, .help = "Mass of the first link", .log = true});
    v("radius", radius, {.unit = "m", .min = 1e-5, .max = 1, .help = "Radius of the first link", .log = true});
    v("taper", taper, {.min = 0.05, .max = 1.0, .help = "Tip radius over root radius"});
    v("damping", damping,
      {.unit = "N m s/rad",
       .min = 0,
       .max = 10,
       .help = "Joint damping on relative angular velocity (root joint)",
       .log = true});
    v("stiffness", stiffness,
      {.unit = "N m/rad",
       .min = 0,
       .max = 100,
       .help = "Bending stiffness toward the rest pose (root joint)",
       .log = true});
    v("stiffness_tip", stiffness_tip,
      {.min = 1e-3,
       .max = 1e3,
       .help = "Tip joint's stiffness over the root's (1: uniform; geometric in between)",
       .log = true});
    v("damping_tip", damping_tip,
      {.min = 1e-3,
       .max = 1e3,
       .help = "Tip joint's damping over the root's (1: uniform; geometric in between)",
       .log = true});
    v("drag", drag, {.unit = "N s/m^2", .min = 0, .max = 100, .help = "Air drag per metre of link", .log = true});
    v("direction", direction,
      {.min = -1, .max = 1, .help = "Initial direction from the anchor", .apply = Apply::Restart});
    v("attach", attach, {.help = "What the first link hangs from", .apply = Apply::Restart});
    v("hinge", hinge,
      {.min = -1,
       .max = 1,
       .help = "The first joint turns only about this axis (world, at t = 0): a hinge; 0 0 0: spherical",
       .apply = Apply::Restart});
    v("servo", servo, {.help = "A servo that turns the root hinge at a given speed", .apply = Apply::Restart});
  }
};

// The anchor of a chain scene: a point whose motion is prescribed analytically.
enum class AnchorMotion { Fixed, Shake, ConstantVelocity };
template <>
struct EnumNames<AnchorMotion> {
  static constexpr std::array<std::string_view, 3> names{"fixed", "shake", "constant_velocity"};
};

struct AnchorParams {
  // fixed: at `position`. shake: position + (0.1 sin(2 pi 1.5 t), 0, 0.05 sin(2 pi 3 t)).
  // constant_velocity: position + velocity t.
  AnchorMotion motion = AnchorMotion::Fixed;
  Eigen::Vector3d position{0.0, 0.0, 0.0};  // m
  Eigen::Vector3d velocity{0.0, 0.0, 0.0};  // m/s, constant_velocity only

  template <class V>
  void reflect(V& v) {
    v("motion", motion, {.help = "Prescribed motion of the anchor point"});
    v("position", position, {.unit = "m", .min = -1e3, .max = 1e3, .help = "Anchor position at t = 0"});
    v("velocity", velocity, {.unit = "m/s", .min = -1e3, .max = 1e3, .help = "Velocity (constant_velocity)"});
  }
};

}  // namespace ponyhop

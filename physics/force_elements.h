// Force elements: external forces that depend on the state (Hecker's F_E, "springs, friction,
// drag"): they add world-frame forces and torques to the bodies' accumulators in the external-
// force stage. Internal pairs (damper, bending spring) apply equal and opposite torques, so they
// never change the total angular momentum. Forces added to kinematic bodies are ignored.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "physics/rigid_body.h"

namespace ponyhop {

class ForceElement {
 public:
  virtual ~ForceElement() = default;
  virtual void apply(std::vector<RigidBody>& bodies) const = 0;
  // Stored energy (conservative elements), J; 0 for dissipative ones.
  virtual double potentialEnergy(const std::vector<RigidBody>& /*bodies*/) const { return 0.0; }
  // Whether the force depends on the bodies' velocities (damping, drag): RATTLE then corrects
  // its second kick with a second evaluation (physics/rattle.h), which position-only forces do
  // not need. True unless an element says otherwise: a wrong true costs an evaluation, a wrong
  // false costs the order.
  virtual bool dependsOnVelocity() const { return true; }
};

using ForceElements = std::vector<std::unique_ptr<ForceElement>>;

// Joint damping on the relative angular velocity: t_b = -c (w_b - w_a), t_a = -t_b.
// Body a may be kWorldBody (-1).
class JointDamper final : public ForceElement {
 public:
  JointDamper(int body_a, int body_b, double c) : a_(body_a), b_(body_b), c_(c) {}
  void apply(std::vector<RigidBody>& bodies) const override;

 private:
  int a_, b_;
  double c_;  // N m s/rad
};

// Bending stiffness: a soft angular spring toward the rest relative orientation.
//   q_rel = q_a^-1 q_b (b in a's frame), q_err = q_rest^-1 q_rel, theta = rotation vector of
//   q_err (b's body frame), world-frame torque t_b = -k R_b theta, t_a = -t_b;
//   energy 1/2 k |theta|^2.
class BendingSpring final : public ForceElement {
 public:
  BendingSpring(int body_a, int body_b, double k, const Eigen::Quaterniond& rest_relative)
      : a_(body_a), b_(body_b), k_(k), rest_(rest_relative.normalized()) {}
  void apply(std::vector<RigidBody>& bodies) const override;
  bool dependsOnVelocity() const override { return false; }  // orientations only (its damping is a JointDamper)
  double potentialEnergy(const std::vector<RigidBody>& bodies) const override;
  Eigen::Vector3d worldError(const std::vector<RigidBody>& bodies) const;  // R_b theta

 private:
  int a_, b_;
  double k_;  // N m/rad
  Eigen::Quaterniond rest_;
};

// Linear air drag on a body's centre: f = -c v.
class LinearDrag final : public ForceElement {
 public:
  LinearDrag(int body, double c) : body_(body), c_(c) {}
  void apply(std::vector<RigidBody>& bodies) const override;

 private:
  int body_;
  double c_;  // N s/m
};

}  // namespace ponyhop

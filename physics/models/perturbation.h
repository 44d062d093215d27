// A mouse perturbation (MuJoCo's viewer, "perturb"): a spring-damper that pulls a material point
// of one body toward a target point the user drags. It enters the step as an ordinary force
// element (external-force stage), so every integrator and the constraint solver see it like
// gravity; it does nothing while no body is grabbed.
//
//   p = x + R r_local (the grabbed point), v_p = v + w x (p - x)
//   F = m (k (p_target - p) - c v_p),  c = 2 zeta sqrt(k)   (a critically damped pull when zeta = 1)
//   torque = (p - x) x F
//
// Scaling by the grabbed body's mass m makes the same drag feel alike on a 12 g hair link and a
// 10 kg hopper body (MuJoCo scales its perturbation by the body mass for the same reason).
// The force is capped (max_accel) so that a wild drag cannot throw the simulation apart.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "physics/force_elements.h"

namespace ponyhop {

// What the user is doing with the mouse; shared between the UI (writes) and the element (reads).
struct PerturbationTarget {
  int body = -1;                                          // grabbed body (-1: none)
  Eigen::Vector3d local_point = Eigen::Vector3d::Zero();  // grabbed point, body frame (m)
  Eigen::Vector3d target = Eigen::Vector3d::Zero();       // where it is pulled to, world (m)
  double stiffness = 400.0;                               // 1/s^2 (k per kg of the grabbed body): a ~3 Hz pull
  double damping = 1.0;                                   // zeta, fraction of critical damping
  double max_accel = 400.0;                               // m/s^2, cap of |F| / m

  bool active() const { return body >= 0; }
  // The spring force on the body at its current state (N), before the cap is applied too.
  Eigen::Vector3d force(const RigidBody& b) const;
  Eigen::Vector3d grabbedPoint(const RigidBody& b) const { return b.pointToWorld(local_point); }
};

class Perturbation final : public ForceElement {
 public:
  explicit Perturbation(std::shared_ptr<const PerturbationTarget> target) : target_(std::move(target)) {}
  void apply(std::vector<RigidBody>& bodies) const override;
  // The pull's damper, while a body is grabbed.
  bool dependsOnVelocity() const override { return target_->active() && target_->damping != 0.0; }

 private:
  std::shared_ptr<const PerturbationTarget> target_;
};

}  // namespace ponyhop

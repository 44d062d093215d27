#include "physics/models/perturbation.h"

#include <cmath>

namespace ponyhop {

Eigen::Vector3d PerturbationTarget::force(const RigidBody& b) const {
  const Eigen::Vector3d p = grabbedPoint(b);
  const Eigen::Vector3d vp = b.velocityAt(p);
  const double k = std::max(stiffness, 0.0);
  const double c = 2.0 * std::max(damping, 0.0) * std::sqrt(k);
  Eigen::Vector3d accel = k * (target - p) - c * vp;
  const double n = accel.norm();
  if (!std::isfinite(n)) return Eigen::Vector3d::Zero();  // a NaN target never reaches the state
  if (n > max_accel) accel *= max_accel / n;
  return b.mass * accel;
}

void Perturbation::apply(std::vector<RigidBody>& bodies) const {
  const PerturbationTarget& t = *target_;
  if (!t.active() || t.body >= static_cast<int>(bodies.size())) return;
  RigidBody& b = bodies[static_cast<size_t>(t.body)];
  if (!b.isDynamic()) return;
  const Eigen::Vector3d f = t.force(b);
  b.force += f;
  b.torque += (t.grabbedPoint(b) - b.x).cross(f);
}

}  // namespace ponyhop

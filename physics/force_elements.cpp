#include "physics/force_elements.h"

#include "physics/constraint.h"

namespace ponyhop {

namespace {
void addTorque(std::vector<RigidBody>& bodies, int i, const Eigen::Vector3d& t) {
  if (i != kWorldBody) bodies[i].torque += t;
}
}  // namespace

void JointDamper::apply(std::vector<RigidBody>& bodies) const {
  const Eigen::Vector3d t_b = -c_ * (bodyOf(bodies, b_).w - bodyOf(bodies, a_).w);
  addTorque(bodies, b_, t_b);
  addTorque(bodies, a_, -t_b);
}

Eigen::Vector3d BendingSpring::worldError(const std::vector<RigidBody>& bodies) const {
  const RigidBody& a = bodyOf(bodies, a_);
  const RigidBody& b = bodyOf(bodies, b_);
  const Eigen::Quaterniond q_rel = a.q.conjugate() * b.q;
  // q_b = q_a q_rest q_err: q_err's axis is in b's body frame, R_b maps it to the world.
  return b.q * rotationVector(rest_.conjugate() * q_rel);
}

void BendingSpring::apply(std::vector<RigidBody>& bodies) const {
  const Eigen::Vector3d t_b = -k_ * worldError(bodies);
  addTorque(bodies, b_, t_b);
  addTorque(bodies, a_, -t_b);
}

double BendingSpring::potentialEnergy(const std::vector<RigidBody>& bodies) const {
  return 0.5 * k_ * worldError(bodies).squaredNorm();
}

void LinearDrag::apply(std::vector<RigidBody>& bodies) const { bodies[body_].force -= c_ * bodies[body_].v; }

}  // namespace ponyhop

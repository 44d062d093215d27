#include "physics/hinge_joint.h"

#include <cmath>

#include "physics/prismatic_joint.h"
#include "physics/soft_constraint.h"
#include "physics/spherical_joint.h"
#include "physics/world.h"

namespace ponyhop {

HingeJoint::HingeJoint(int body_a, const Eigen::Vector3d& point_a, const Eigen::Vector3d& axis_a, int body_b,
                       const Eigen::Vector3d& point_b, const Eigen::Vector3d& axis_b)
    : Constraint(body_a, body_b),
      point_a_(point_a),
      point_b_(point_b),
      axis_a_(axis_a.normalized()),
      axis_b_(axis_b.normalized()) {
  // Any two unit vectors across b's axis: the one of the frame's axes least along it, made
  // orthogonal, and their cross product.
  Eigen::Index k;
  axis_b_.cwiseAbs().minCoeff(&k);
  across_b_[0] = (Eigen::Vector3d::Unit(k) - axis_b_(k) * axis_b_).normalized();
  across_b_[1] = axis_b_.cross(across_b_[0]);
}

std::unique_ptr<HingeJoint> HingeJoint::at(const RigidBody& a, int body_a, const RigidBody& b, int body_b,
                                           const Eigen::Vector3d& pivot, const Eigen::Vector3d& axis) {
  const Eigen::Vector3d n = axis.normalized();
  return std::make_unique<HingeJoint>(body_a, a.q.conjugate() * (pivot - a.x), a.q.conjugate() * n, body_b,
                                      b.q.conjugate() * (pivot - b.x), b.q.conjugate() * n);
}

void HingeJoint::evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const {
  ConstraintRows point;  // fixed-capacity storage: no heap allocation
  SphericalJoint(bodyA(), point_a_, bodyB(), point_b_).evaluate(a, b, point);
  out.C.resize(5);
  out.ja.resize(5, 6);
  out.jb.resize(5, 6);
  out.bias.resize(5);
  out.C.head<3>() = point.C;
  out.ja.topRows<3>() = point.ja;
  out.jb.topRows<3>() = point.jb;
  out.bias.head<3>() = point.bias;
  const Eigen::Vector3d n = a.q * axis_a_;
  for (int i = 0; i < 2; ++i) {
    const JointRow r = dotRow(a, n, b, b.q * across_b_[i]);
    out.C(3 + i) = r.C;
    out.ja.row(3 + i) = r.ja;
    out.jb.row(3 + i) = r.jb;
    out.bias(3 + i) = r.bias;
  }
}

double HingeJoint::error(const ConstraintRows& rows) const {
  return std::max(rows.C.head<3>().norm(), rows.C.tail<2>().cwiseAbs().maxCoeff());
}

HingeServo::HingeServo(const std::vector<RigidBody>& bodies, const HingeJoint& hinge, double speed, double stiffness,
                       double damping)
    : a_(hinge.bodyA()),
      b_(hinge.bodyB()),
      axis_a_(hinge.axisA()),
      axis_b_(hinge.axisB()),
      rest_((bodyOf(bodies, a_).q.conjugate() * bodyOf(bodies, b_).q).normalized()),
      speed_(speed),
      stiffness_(stiffness),
      damping_(damping) {}

double HingeServo::error(const std::vector<RigidBody>& bodies, double t) const {
  const Eigen::Quaterniond rel = bodyOf(bodies, a_).q.conjugate() * bodyOf(bodies, b_).q;
  const Eigen::Quaterniond target = rest_ * Eigen::Quaterniond(Eigen::AngleAxisd(speed_ * t, axis_b_));
  const Eigen::Quaterniond err = target.conjugate() * rel;  // b from its target, in b's frame
  // Half-angle form of the rotation about the axis, the shorter way round (w >= 0).
  const double s = err.vec().dot(axis_b_), c = err.w();
  return c < 0.0 ? 2.0 * std::atan2(-s, -c) : 2.0 * std::atan2(s, c);
}

void HingeServo::applyForces(World& world, double t) {
  std::vector<RigidBody>& bodies = world.bodies();
  const RigidBody& a = bodyOf(bodies, a_);
  const Eigen::Vector3d n = a.q * axis_a_;
  const double rate = (bodyOf(bodies, b_).w - a.w).dot(n);
  const Eigen::Vector3d tau = -softConstraintForce(stiffness_, damping_, error(bodies, t), 0.0, rate, speed_) * n;
  if (dynamicBody(bodies, b_)) bodies[size_t(b_)].torque += tau;
  if (dynamicBody(bodies, a_)) bodies[size_t(a_)].torque -= tau;
}

}  // namespace ponyhop

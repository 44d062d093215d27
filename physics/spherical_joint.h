// A spherical (ball) joint: a point fixed in body a coincides with a point fixed in body b.
// Three rows, no rotational constraint. The ponytail's joints and the hopper's hip.
#pragma once

#include <Eigen/Core>

#include "physics/constraint.h"

namespace ponyhop {

class SphericalJoint final : public Constraint {
 public:
  // point_a: the joint point in a's body frame (relative to a's centre of mass);
  // point_b: the same point in b's body frame. Either body may be kWorldBody (then the point
  // is in world coordinates).
  SphericalJoint(int body_a, const Eigen::Vector3d& point_a, int body_b, const Eigen::Vector3d& point_b)
      : Constraint(body_a, body_b), point_a_(point_a), point_b_(point_b) {}

  int dimension() const override { return 3; }
  const char* typeName() const override { return "spherical"; }
  void evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const override;

  const Eigen::Vector3d& pointA() const { return point_a_; }
  const Eigen::Vector3d& pointB() const { return point_b_; }

 private:
  Eigen::Vector3d point_a_;
  Eigen::Vector3d point_b_;
};

}  // namespace ponyhop

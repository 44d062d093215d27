// A hinge (revolute) joint: a point fixed in body a coincides with a point fixed in body b, and
// an axis fixed in a stays parallel to an axis fixed in b. Five rows, one free rotation about the
// axis: the four-bar's ground pivots (assets/scenes/four_bar.json), and the joint a servo drives.
//
//   rows 0-2   the spherical joint's rows: C = p_a - p_b (metres)
//   rows 3-4   dot-product rows (physics/prismatic_joint.h, dotRow): C = n_a . t_1, n_a . t_2,
//              n_a the axis fixed in a, t_1, t_2 unit vectors fixed in b across b's axis n_b
//              (b's axis stays parallel to a's: the two rotations across the axis are held)
//
// A hinge is the smallest joint that removes the spurious freedoms of a linkage built from ball
// joints: a four-bar of four spherical joints can fold out of its plane, one of four parallel
// hinges over-constrains it (a redundant row in 3D). The spatial RSSR four-bar (hinge crank,
// spherical coupler ends, hinge rocker) has mobility 1 plus the coupler's idle spin.
//
// featherstone keeps a hinge as a loop joint always (its rows solved in joint space, as any loop
// joint's): a body held only by hinges is a free body of the tree closed by their rows.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "physics/constraint.h"
#include "physics/controller.h"

namespace ponyhop {

class HingeJoint final : public Constraint {
 public:
  // point_a / point_b: the pivot in a's / b's body frame; axis_a / axis_b: the hinge axis in a's /
  // b's body frame (unit; they are the same world axis at the pose the joint is made at). Either
  // body may be kWorldBody (then its point and axis are in world coordinates).
  HingeJoint(int body_a, const Eigen::Vector3d& point_a, const Eigen::Vector3d& axis_a, int body_b,
             const Eigen::Vector3d& point_b, const Eigen::Vector3d& axis_b);
  // The hinge about `axis` (world) through the world point `pivot`, between a and b as they are
  // now.
  static std::unique_ptr<HingeJoint> at(const RigidBody& a, int body_a, const RigidBody& b, int body_b,
                                        const Eigen::Vector3d& pivot, const Eigen::Vector3d& axis);

  int dimension() const override { return 5; }
  const char* typeName() const override { return "hinge"; }
  void evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const override;
  // The larger of the points' gap (m) and the largest axis row (the sine of the axes' angle).
  double error(const ConstraintRows& rows) const override;

  const Eigen::Vector3d& pointA() const { return point_a_; }
  const Eigen::Vector3d& pointB() const { return point_b_; }
  const Eigen::Vector3d& axisA() const { return axis_a_; }
  const Eigen::Vector3d& axisB() const { return axis_b_; }

 private:
  Eigen::Vector3d point_a_, point_b_;
  Eigen::Vector3d axis_a_, axis_b_;
  Eigen::Vector3d across_b_[2];  // t_1, t_2 in b's frame
};

// A servo that turns a hinge at a given speed: a PD soft constraint (physics/soft_constraint.h)
// on the hinge angle theta of b relative to a, toward theta_0 + speed t:
//
//   e   = angle about the axis of q_target^-1 q_rel,  q_rel = q_a^-1 q_b,
//         q_target = q_rest rot(axis_b, speed t)            (q_rest: q_rel when the servo is made)
//   tau = -(k_s e + k_d ((w_b - w_a) . n - speed)) n      on b, -tau on a  (n = R_a axis_a)
//
// e is taken in (-pi, pi] (the shorter way round; the force law jumps only at e = pi, half a turn
// behind, which a servo that holds its target never reaches). The torques are equal and opposite,
// so the pair never changes the total angular momentum; it does work (it drives the linkage).
class HingeServo final : public Controller {
 public:
  HingeServo(const std::vector<RigidBody>& bodies, const HingeJoint& hinge, double speed, double stiffness,
             double damping);
  void applyForces(World& world, double t) override;
  bool dependsOnVelocity() const override { return damping_ != 0.0; }
  // The angle error e above at time t (rad).
  double error(const std::vector<RigidBody>& bodies, double t) const;

 private:
  int a_, b_;
  Eigen::Vector3d axis_a_, axis_b_;
  Eigen::Quaterniond rest_;
  double speed_, stiffness_, damping_;
};

}  // namespace ponyhop

// A prismatic (sliding) joint: body b slides along one axis fixed in body a, without turning
// relative to it. Five rows, one free degree of freedom: the hopper's knee (Hecker lecture,
// "Hopper Knee": "joint subtracts 5 DOF ... 3 rotational, 2 translational").
//
// Frames. The joint frame of a (axes x_a, y_a, z_a, z_a the sliding axis, Hecker's t_a) and the
// joint frame of b (x_b, y_b, z_b, Hecker's n1, n2, ...) are fixed in the bodies; in the rest
// pose they coincide. p_a and p_b are points fixed in a and b that lie on the sliding axis.
//
//   rotational (dot products of body-fixed unit vectors, Hecker lecture: "t_a . n1 = 0, t_a . n2 = 0,
//   n3 . n2 = 0"):
//     C1 = z_a . x_b,   C2 = z_a . y_b        (b's axis stays parallel to a's: 2 rotations)
//     C3 = x_a . y_b                          (no twist about the axis: the third rotation)
//   translational (Hecker lecture: "(R_b - R_a) . n1 = 0, (R_b - R_a) . n2 = 0", n's in a's frame):
//     C4 = (p_b - p_a) . x_a,   C5 = (p_b - p_a) . y_a
//
// The free coordinate is the slide s = (p_b - p_a) . z_a (slide()), driven by soft constraints
// (the leg spring), not by this joint. Derivations of J and J'q' are above the two row builders
// (dotRow, axisRow), which the ground contact reuses.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "physics/constraint.h"

namespace ponyhop {

// One row of a dot-product constraint C = s . t between a unit vector s fixed in a and t fixed
// in b (world-frame vectors as they are now). Fills C, the angular Jacobian columns and J'q'.
struct JointRow {
  double C = 0.0;
  Eigen::Matrix<double, 1, 6> ja = Eigen::Matrix<double, 1, 6>::Zero();
  Eigen::Matrix<double, 1, 6> jb = Eigen::Matrix<double, 1, 6>::Zero();
  double bias = 0.0;
};
JointRow dotRow(const RigidBody& a, const Eigen::Vector3d& s, const RigidBody& b, const Eigen::Vector3d& t);
// One row of C = (p_b - p_a) . u, u a unit vector fixed in a, p_a / p_b points fixed in a / b
// (world positions as they are now).
JointRow axisRow(const RigidBody& a, const Eigen::Vector3d& p_a, const Eigen::Vector3d& u, const RigidBody& b,
                 const Eigen::Vector3d& p_b);

class PrismaticJoint final : public Constraint {
 public:
  // point_a / point_b: points on the sliding axis in a's / b's body frame. frame_a / frame_b:
  // the joint frame's orientation in a's / b's body frame (z = sliding axis). Either body may be
  // kWorldBody (then its point and frame are in world coordinates).
  PrismaticJoint(int body_a, const Eigen::Vector3d& point_a, const Eigen::Quaterniond& frame_a, int body_b,
                 const Eigen::Vector3d& point_b, const Eigen::Quaterniond& frame_b)
      : Constraint(body_a, body_b),
        point_a_(point_a),
        point_b_(point_b),
        frame_a_(frame_a.normalized()),
        frame_b_(frame_b.normalized()) {}

  int dimension() const override { return 5; }
  const char* typeName() const override { return "prismatic"; }
  void evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const override;
  // The largest violation of the five rows: max |C_i| (rows 1-3 are sines of small angles, rows
  // 4-5 metres).
  double error(const ConstraintRows& rows) const override { return rows.C.cwiseAbs().maxCoeff(); }

  // The free coordinate: s = (p_b - p_a) . z_a (m).
  double slide(const RigidBody& a, const RigidBody& b) const;
  // The sliding axis z_a in the world.
  Eigen::Vector3d axis(const RigidBody& a) const { return a.q * (frame_a_ * Eigen::Vector3d::UnitZ()); }

 private:
  Eigen::Vector3d point_a_;
  Eigen::Vector3d point_b_;
  Eigen::Quaterniond frame_a_;
  Eigen::Quaterniond frame_b_;
};

}  // namespace ponyhop

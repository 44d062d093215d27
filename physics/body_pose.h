// Poses of every body at any time: states recorded at step boundaries, and the state between two
// of them by cubic Hermite interpolation (positions from x and v, orientations from q and q' =
// (0, w) q / 2 then normalized). The interpolant matches both end states and their first
// derivatives, so its error is O(h^4) in position and orientation and O(h^3) in velocity for a
// smooth motion (h: the step); a requested time that falls on a step gives that step's state
// exactly. Across an impulse (a contact that changes velocities within the step) it is only as
// good as the neighbouring states.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "physics/rigid_body.h"

namespace ponyhop {

struct BodyPose {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();            // m, centre of mass (body origin), world
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // body to world
  Eigen::Vector3d v = Eigen::Vector3d::Zero();            // m/s
  Eigen::Vector3d w = Eigen::Vector3d::Zero();            // rad/s, world frame
};

// The poses of all bodies at one time.
struct PoseFrame {
  double t = 0.0;
  std::vector<BodyPose> bodies;
};

// Into `out`, reusing its storage (a frame captured at every step allocates nothing once sized).
void capturePoses(double t, const std::vector<RigidBody>& bodies, PoseFrame& out);

// The state at time t in [a.t, b.t] (clamped) between two frames of the same bodies.
PoseFrame interpolatePoses(const PoseFrame& a, const PoseFrame& b, double t);
BodyPose interpolatePose(const BodyPose& a, const BodyPose& b, double h, double s);  // s in [0, 1]

}  // namespace ponyhop

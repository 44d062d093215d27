// Kinematic bodies move as prescribed (keyframes, an analytic anchor path). The constraint
// equations need their velocity AND acceleration (Hecker lecture, "Kinematic Control"): a
// kinematic parent must always carry analytic derivatives consistent with its pose.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>

namespace ponyhop {

// Pose and its first two time derivatives, world frame.
struct KinematicState {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();            // m, centre of mass / origin
  Eigen::Vector3d v = Eigen::Vector3d::Zero();            // m/s
  Eigen::Vector3d a = Eigen::Vector3d::Zero();            // m/s^2
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // body to world
  Eigen::Vector3d w = Eigen::Vector3d::Zero();            // rad/s, angular velocity, world frame
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();        // rad/s^2, angular acceleration, world frame
};

// A prescribed motion: the full kinematic state at time t (s). Must be twice differentiable.
using KinematicMotion = std::function<KinematicState(double t)>;

}  // namespace ponyhop

#include "engine/camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ponyhop {

static double deg2rad(double d) { return d * std::numbers::pi / 180.0; }

Eigen::Matrix4d Camera::view() const {
  Eigen::Vector3d f = (target - eye);
  if (f.norm() < 1e-12) f = Eigen::Vector3d(0, 1, 0);
  f.normalize();
  Eigen::Vector3d u = up.normalized();
  Eigen::Vector3d s = f.cross(u);
  if (s.norm() < 1e-9) {  // looking straight along `up`: pick any side vector
    s = f.cross(Eigen::Vector3d(0, 1, 0));
    if (s.norm() < 1e-9) s = f.cross(Eigen::Vector3d(1, 0, 0));
  }
  s.normalize();
  u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Eigen::Matrix4d Camera::projection(double aspect, double n, double f) const {
  const double t = 1.0 / std::tan(deg2rad(fov) * 0.5);
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (f + n) / (n - f);
  m(2, 3) = 2.0 * f * n / (n - f);
  m(3, 2) = -1.0;
  return m;
}

static Camera orbitCamera(const CameraParams& p, const Eigen::Vector3d& center, double azimuth_deg) {
  Camera c;
  c.fov = p.fov;
  c.target = center;
  const double a = deg2rad(azimuth_deg);
  c.eye = center + Eigen::Vector3d(p.orbit_distance * std::cos(a), p.orbit_distance * std::sin(a), p.orbit_height);
  return c;
}

Camera cameraAt(const CameraParams& p, double t, const Eigen::Vector3d* followed) {
  switch (p.mode) {
    case CameraMode::Orbit:
      return orbitCamera(p, p.target, p.orbit_angle + p.orbit_speed * t);
    case CameraMode::Follow:
      return orbitCamera(p, followed ? *followed : p.target, p.orbit_angle);
    case CameraMode::Fixed:
    default: {
      Camera c;
      c.eye = p.position;
      c.target = p.target;
      c.fov = p.fov;
      return c;
    }
  }
}

Camera FollowCamera::update(const CameraParams& p, double t, const Eigen::Vector3d& followed, double dt) {
  if (!initialized_ || !(dt > 0.0)) {
    if (!initialized_) {
      z_ = followed.z();
      vz_ = 0.0;
      initialized_ = true;
    }
  } else {
    // Critically damped spring z'' = w^2 (target - z) - 2 w z', w = 1/tau, integrated exactly
    // enough with small substeps (semi-implicit Euler; dt of a video frame is 1/30 s).
    const double w = 1.0 / tau_;
    const int n = std::max(1, int(std::ceil(dt / 0.005)));
    const double h = dt / n;
    for (int i = 0; i < n; ++i) {
      vz_ += h * (w * w * (followed.z() - z_) - 2.0 * w * vz_);
      z_ += h * vz_;
    }
  }
  Eigen::Vector3d center(followed.x(), followed.y(), z_);
  (void)t;
  return orbitCamera(p, center, p.orbit_angle);
}

}  // namespace ponyhop

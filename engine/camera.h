// The view: a perspective pinhole camera (world z up) and how CameraParams place it over time.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sim/scene.h"

namespace ponyhop {

struct Camera {
  Eigen::Vector3d eye{0.9, -1.4, 0.55};
  Eigen::Vector3d target{0.0, 0.0, 0.0};
  Eigen::Vector3d up{0.0, 0.0, 1.0};
  double fov = 35.0;   // deg, vertical
  double znear = 0.0;  // m; 0: chosen by the renderer from the scene bounds
  double zfar = 0.0;   // m; 0: chosen by the renderer (covers the faded ground)

  // Right-handed look-at (camera looks down its -z), as in gluLookAt.
  Eigen::Matrix4d view() const;
  // OpenGL clip space (z in -1..1). aspect = width / height.
  Eigen::Matrix4d projection(double aspect, double near_m, double far_m) const;
};

// Camera at time t (s) for CameraParams, stateless:
//   fixed:  eye = position, looking at target.
//   orbit:  azimuth = orbit_angle + orbit_speed * t (deg, from +x toward +y) around target, at
//           horizontal distance orbit_distance and orbit_height above the target.
//   follow: like orbit without turning (azimuth = orbit_angle) around `followed` (when given,
//           else around target); see FollowCamera for the smoothed version.
Camera cameraAt(const CameraParams& p, double t, const Eigen::Vector3d* followed = nullptr);

// Follow mode with a steadier view: the target tracks the body exactly in x and y but its height
// follows through a critically damped spring (time constant `tau`), so a hopping body does not
// shake the picture up and down. Deterministic: depends only on the sequence of update() calls.
class FollowCamera {
 public:
  explicit FollowCamera(double tau = 0.35) : tau_(tau) {}
  // dt: time since the previous update (s); the first call snaps to the body.
  Camera update(const CameraParams& p, double t, const Eigen::Vector3d& followed, double dt);
  void reset() { initialized_ = false; }

 private:
  double tau_;
  bool initialized_ = false;
  double z_ = 0.0, vz_ = 0.0;
};

}  // namespace ponyhop

// The head's keyframed motion: a C2 curve through key poses, evaluated with analytic velocity,
// acceleration, angular velocity and angular acceleration (docs/ANIMATION.md).
//
// Why C2: the chain hanging from the head is solved with the head's acceleration in its
// constraint equations (physics/kinematic.h). Catmull-Rom, cubic Hermite and SQUAD are only C1:
// their acceleration jumps at every key and kicks the ponytail. Here both the position and the
// orientation are cubic splines (C2) in time:
//   position      x(t) = cubic spline through the key positions,
//   orientation   q(t) = q0 exp(r(t)), r(t) = cubic spline through the keys' rotation vectors
//                 r_i = log(q0^-1 q_i), unwrapped so that consecutive keys take the nearest
//                 of the equivalent vectors (r + 2 pi k n): a 720 degree spin stays a spin.
// End conditions:
//   loop   periodic spline (value, slope and curvature agree at the seam),
//   clamp  the pose is held before the first and after the last key with zero velocity AND
//          zero acceleration, so the spline ends with v = 0 and a = 0. A cubic spline has one
//          end condition per end; the second one comes from one extra, free (non-interpolated)
//          knot inside the first and the last interval. The held pose then joins the curve C2.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "physics/kinematic.h"
#include "physics/models/keyframe_params.h"
#include "physics/status.h"

namespace ponyhop {

// A sampled pose (e.g. imported from a mesh file's animation): time, position, orientation.
struct PoseSample {
  double t = 0.0;                                                // s
  Eigen::Vector3d position = Eigen::Vector3d::Zero();            // m, world frame
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // body to world (normalized on use)
};

// How a track is played.
struct TrackOptions {
  LoopMode mode = LoopMode::Loop;
  double speed = 1.0;      // playback rate: clip time = speed * t
  double amplitude = 1.0;  // scales each key's offset from the first key (0: frozen at key 0)
};
TrackOptions trackOptions(const AnimationParams& params);

// Unit quaternion of Euler angles in degrees about x, y, z with R = Rz Ry Rx.
Eigen::Quaterniond eulerDegToQuat(const Eigen::Vector3d& deg);

// q = exp(r) for a rotation vector r (angle |r| about r/|r|: q = (cos(|r|/2), sin(|r|/2) r/|r|)),
// and its first two time derivatives when r(t) has derivatives dr, ddr. Exact (a second-order
// jet pushed through the exponential), with series near |r| = 0.
struct QuatJet {
  Eigen::Quaterniond q, dq, ddq;  // q, dq/dt, d2q/dt2 (dq, ddq are not unit quaternions)
};
QuatJet expRotationVector(const Eigen::Vector3d& r, const Eigen::Vector3d& dr, const Eigen::Vector3d& ddr);

// World-frame angular velocity and acceleration of q(t): w = 2 vec(q' q^-1),
// alpha = dw/dt = 2 vec(q'' q^-1) (the other term, 2 q' (q^-1)' = -2 q' conj(q'), is real).
Eigen::Vector3d angularVelocity(const QuatJet& j);
Eigen::Vector3d angularAcceleration(const QuatJet& j);

class KeyframeTrack {
 public:
  // From keys of the scene file / clips (rotation: Euler degrees) into `track`. On bad input
  // returns an error that names the key index and the field, and leaves `track` as it was.
  static Status fromKeyframes(const std::vector<Keyframe>& keys, const TrackOptions& options, KeyframeTrack& track);
  // From pose samples (quaternions; need not be normalized, must not be zero).
  static Status fromSamples(const std::vector<PoseSample>& samples, const TrackOptions& options, KeyframeTrack& track);

  // Pose, velocity, acceleration, orientation, angular velocity and angular acceleration (world
  // frame) at time t (s), all analytic. Clip time is speed * t.
  KinematicState evaluate(double t) const;

  // First and last key time (clip time, s) and the period of a loop (clip time, s; includes the
  // closing segment when the loop was closed automatically). period() is 0 for a constant track.
  double startTime() const;
  double endTime() const;
  double period() const;
  LoopMode mode() const;

 private:
  struct Data;
  std::shared_ptr<const Data> d_;  // immutable after construction: copies are cheap and thread-safe
};

// A KinematicMotion (std::function) that plays the track.
KinematicMotion makeMotion(const KeyframeTrack& track);
// Shortcut for keys + options into `motion`; the error of fromKeyframes on bad input.
Status makeMotion(const std::vector<Keyframe>& keys, const TrackOptions& options, KinematicMotion& motion);

}  // namespace ponyhop

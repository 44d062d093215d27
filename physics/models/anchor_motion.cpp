#include "physics/models/anchor_motion.h"

#include <cmath>
#include <numbers>

namespace ponyhop {

KinematicMotion anchorMotion(const AnchorParams& params) {
  const Eigen::Vector3d p0 = params.position;
  switch (params.motion) {
    case AnchorMotion::Fixed:
      return [p0](double) {
        KinematicState s;
        s.x = p0;
        return s;
      };
    case AnchorMotion::Shake:
      return [p0](double t) {
        // x: amplitude 0.1 m at 1.5 Hz; z: 0.05 m at 3 Hz. d/dt sin(wt) = w cos(wt), etc.
        constexpr double wx = 2.0 * std::numbers::pi * 1.5;
        constexpr double wz = 2.0 * std::numbers::pi * 3.0;
        constexpr double ax = 0.1, az = 0.05;
        KinematicState s;
        s.x = p0 + Eigen::Vector3d(ax * std::sin(wx * t), 0.0, az * std::sin(wz * t));
        s.v = Eigen::Vector3d(ax * wx * std::cos(wx * t), 0.0, az * wz * std::cos(wz * t));
        s.a = Eigen::Vector3d(-ax * wx * wx * std::sin(wx * t), 0.0, -az * wz * wz * std::sin(wz * t));
        return s;
      };
    case AnchorMotion::ConstantVelocity:
      return [p0, v = params.velocity](double t) {
        KinematicState s;
        s.x = p0 + v * t;
        s.v = v;
        return s;
      };
  }
  return nullptr;
}

}  // namespace ponyhop

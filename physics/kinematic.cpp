#include "physics/kinematic.h"

namespace ponyhop {

KinematicMotion staticMotion(const Eigen::Vector3d& x, const Eigen::Quaterniond& q) {
  KinematicState s;
  s.x = x;
  s.q = q.normalized();
  return [s](double) { return s; };
}

}  // namespace ponyhop

#include "physics/hopper_collisions.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <numbers>

namespace ponyhop {

HopperShapes addHopperShapes(Collisions& col, const HopperModel& m, int ground) {
  const HopperParams& p = m.params;
  HopperShapes s;
  // The hull: a capsule along the body's x axis, radius half the body's height (engine/scene_draw.cpp).
  const double rz = 0.5 * p.body_size.z();
  const double half = std::max(0.5 * p.body_size.x() - rz, 0.0);
  const Eigen::Quaterniond z_to_x(Eigen::AngleAxisd(0.5 * std::numbers::pi, Eigen::Vector3d::UnitY()));
  s.body = col.addShape(m.body, Shape::capsule(half, rz, rz, Eigen::Vector3d::Zero(), z_to_x));
  // The side pods: from x = -0.55 hx (radius 0.55 rz) to x = +0.35 hx (radius 0.45 rz), beside the hull.
  const double hx = 0.5 * p.body_size.x(), side = 0.75 * 0.5 * p.body_size.y() + 0.3 * rz;
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector3d at(-0.1 * hx, k == 0 ? side : -side, -0.1 * rz);
    s.pods[k] = col.addShape(m.body, Shape::capsule(0.45 * hx, 0.45 * rz, 0.55 * rz, at, z_to_x));
  }
  // The upper leg: hip end (+z) to its lower end, tapering to 0.8 of its radius.
  s.upper = col.addShape(m.upper, Shape::capsule(0.5 * p.upper_length, p.upper_radius, 0.8 * p.upper_radius));
  // The foot's rod: from its upper end (+z) down to two toe radii above the toe's centre.
  const double top = 0.5 * p.foot_length, bottom = m.toe_in_foot.z() + 2.0 * p.toe_radius;
  if (top > bottom) {
    s.foot = col.addShape(m.foot, Shape::capsule(0.5 * (top - bottom), p.foot_radius, 0.8 * p.foot_radius,
                                                 Eigen::Vector3d(0.0, 0.0, 0.5 * (top + bottom))));
  }
  s.toe = col.addShape(m.foot, Shape::sphere(p.toe_radius, m.toe_in_foot));
  if (ground >= 0) {
    for (int shape : {s.body, s.pods[0], s.pods[1], s.upper, s.foot})
      if (shape >= 0) col.addPair(shape, ground, p.friction);
  }
  return s;
}

void pairHoppers(Collisions& col, const HopperShapes& a, const HopperShapes& b) {
  for (int x : a.all())
    for (int y : b.all())
      if (x >= 0 && y >= 0) col.addPair(x, y);
}

}  // namespace ponyhop

#include "physics/models/hopper_collisions.h"

#include <Eigen/Geometry>
#include <algorithm>

#include "physics/rigid_body.h"

namespace ponyhop {

std::array<CapsuleSpan, 3> hopperHull(const HopperParams& p) {
  const Eigen::Vector3d half = 0.5 * p.body_size;
  const double rz = half.z();
  const double ry = 0.75 * half.y();
  const double side = ry + 0.3 * rz;
  return {CapsuleSpan{Eigen::Vector3d(-(half.x() - rz), 0.0, 0.0), Eigen::Vector3d(half.x() - rz, 0.0, 0.0), rz, rz},
          CapsuleSpan{Eigen::Vector3d(-0.55 * half.x(), side, -0.1 * rz),
                      Eigen::Vector3d(0.35 * half.x(), side, -0.1 * rz), 0.55 * rz, 0.45 * rz},
          CapsuleSpan{Eigen::Vector3d(-0.55 * half.x(), -side, -0.1 * rz),
                      Eigen::Vector3d(0.35 * half.x(), -side, -0.1 * rz), 0.55 * rz, 0.45 * rz}};
}

namespace {

// A span as a Shape: its z axis from b toward a, centred between them.
Shape capsuleOf(const CapsuleSpan& c) {
  const Eigen::Vector3d axis = c.a - c.b;
  const double length = axis.norm();
  const Eigen::Quaterniond rot =
      length > 0.0 ? rotationBetween(Eigen::Vector3d::UnitZ(), axis) : Eigen::Quaterniond::Identity();
  return Shape::capsule(0.5 * length, c.ra, c.rb, 0.5 * (c.a + c.b), rot);
}

}  // namespace

HopperShapes addHopperShapes(Collisions& col, const HopperModel& m, const std::vector<int>& scenery) {
  const HopperParams& p = m.params;
  HopperShapes s;
  const std::array<CapsuleSpan, 3> hull = hopperHull(p);
  s.body = col.addShape(m.body, capsuleOf(hull[0]));
  s.pods[0] = col.addShape(m.body, capsuleOf(hull[1]));
  s.pods[1] = col.addShape(m.body, capsuleOf(hull[2]));
  // The upper leg: hip end (+z) to its lower end, tapering to 0.8 of its radius.
  s.upper = col.addShape(m.upper, Shape::capsule(0.5 * p.upper_length, p.upper_radius, 0.8 * p.upper_radius));
  // The foot's rod: from its upper end (+z) down to two toe radii above the toe's centre.
  const double top = 0.5 * p.foot_length, bottom = m.toe_in_foot.z() + 2.0 * p.toe_radius;
  if (top > bottom) {
    s.foot = col.addShape(m.foot, Shape::capsule(0.5 * (top - bottom), p.foot_radius, 0.8 * p.foot_radius,
                                                 Eigen::Vector3d(0.0, 0.0, 0.5 * (top + bottom))));
  }
  s.toe = col.addShape(m.foot, Shape::sphere(p.toe_radius, m.toe_in_foot));
  for (int ground : scenery)
    for (int shape : {s.body, s.pods[0], s.pods[1], s.upper, s.foot})
      if (shape >= 0) col.addPair(shape, ground, p.friction);
  return s;
}

void pairHoppers(Collisions& col, const HopperShapes& a, const HopperShapes& b) {
  for (int x : a.all())
    for (int y : b.all())
      if (x >= 0 && y >= 0) col.addPair(x, y);
}

}  // namespace ponyhop

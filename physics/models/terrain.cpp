#include "physics/models/terrain.h"

#include <cmath>
#include <numbers>

namespace ponyhop {

Terrain::Terrain(const std::vector<TerrainBox>& boxes) {
  const double deg = std::numbers::pi / 180.0;
  for (const TerrainBox& b : boxes) {
    const Eigen::Quaterniond q = Eigen::AngleAxisd(b.rotation.z() * deg, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(b.rotation.y() * deg, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(b.rotation.x() * deg, Eigen::Vector3d::UnitX());
    shapes_.push_back(Shape::box(0.5 * b.size, b.center, q));
  }
}

Terrain::Surface Terrain::at(const Eigen::Vector3d& x) const {
  Surface s;
  s.distance = x.z();  // the plane z = 0: n = +z, level 0
  for (const Shape& box : shapes_) {
    Eigen::Vector3d n;
    const double d = signedDistance(place(box, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()), x, &n);
    if (d < s.distance) {
      s.distance = d;
      s.normal = n;
      s.level = n.dot(x) - d;
    }
  }
  return s;
}

}  // namespace ponyhop

// The ground: the plane z = 0 and boxes fixed in the world standing on it or in it (a step is a
// box, a slope a tilted box), taken together as one solid, their union. Eigen only.
//
// The hopper's toe (physics/models/hopper_foot.h, GroundContact) asks it for the tangent plane under the toe:
// the nearest solid's signed distance, its outward normal and the plane's level n . y = level. The
// union's signed distance is the least of the solids' (exact outside the union, which is where a
// contact is looked for). The plane z = 0 answers first on a tie, with n = +z and level 0 exactly,
// so a scene without boxes gives the same numbers, bit for bit, as the plane alone.
// The bodies' and legs' capsules (collision.ground) meet the same boxes through Collisions.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "physics/reflect.h"
#include "physics/shapes.h"

namespace ponyhop {

struct TerrainBox {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();    // m, world
  Eigen::Vector3d size = Eigen::Vector3d::Ones();      // m, full edge lengths along the box's axes
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // deg, Euler angles about x, y, z (R = Rz Ry Rx)

  template <class V>
  void reflect(V& v) {
    v("center", center, {.unit = "m", .min = -1e4, .max = 1e4, .help = "Centre of the box (world)"});
    v("size", size, {.unit = "m", .min = 1e-3, .max = 1e4, .help = "Edge lengths along the box's own x, y, z"});
    v("rotation", rotation,
      {.unit = "deg",
       .min = -360,
       .max = 360,
       .help = "Euler angles about x, y, z (R = Rz Ry Rx): a slope is a tilted box"});
  }
};

class Terrain {
 public:
  Terrain() = default;
  explicit Terrain(const std::vector<TerrainBox>& boxes);

  struct Surface {
    double distance = 0.0;                              // signed, m (negative inside)
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // outward, unit, world
    double level = 0.0;                                 // the tangent plane: normal . y = level
  };
  // The ground's tangent plane nearest to x.
  Surface at(const Eigen::Vector3d& x) const;

  // The boxes as world-fixed shapes (Shape::box with the box's pose).
  const std::vector<Shape>& shapes() const { return shapes_; }
  bool flat() const { return shapes_.empty(); }

 private:
  std::vector<Shape> shapes_;
};

}  // namespace ponyhop

// Collision shapes and their closest points (narrow phase). Eigen only.
//
// Every shape is placed in its body's frame by a local pose (offset, rotation). Shapes:
//   sphere           centre, radius
//   capsule          a segment along the shape's z from +half_length (end "a", the link's top) to
//                    -half_length (end "b"), with radius_a at a and radius_b at b, linearly in between:
//                    a tapered capsule (the union of the spheres along the segment, a "round cone").
//                    The ponytail's links are drawn exactly so (Chain::segments).
//   box              half extents
//   plane            the shape's z = 0 plane, solid below (the outward normal is the shape's +z)
//   sdf              a signed distance grid (physics/mesh_sdf.h) sampled from a triangle mesh
//
// How a pair is measured. Sphere and capsule are "rounded" shapes: a core (a point or a segment
// p(s), s in [0, 1]) swept by a radius r(s). A box is taken as its 8 corners (points of radius 0).
// The other shape b of the pair is asked only for its signed distance D_b(x) and gradient.
// The gap between a rounded shape and b is
//     gap = min_s  D_b(p(s)) - r(s),
// exact for every pair: the union of the balls touches b where this is smallest. For a convex b
// (sphere, capsule, box, plane) D_b is a convex function of space, D_b(p(s)) - r(s) is convex in s
// and the minimum is found by golden-section search to 1e-12 of the segment; for an sdf it is
// sampled at half the grid's cell, only where the grid's Lipschitz bound leaves room for a value
// below the best sample and below reach (a link far from the head costs two samples), and refined
// around the smallest sample to a thirtieth of a cell. The contact normal is
// grad D_b at the core point (unit; from b towards a), the contact point midway between the two
// surfaces. Signed distances and gradients of the convex shapes are analytic; a capsule's is
// itself a minimum over its own segment (convex, golden section).
//
// Box against box is corner-against-box only (edge-edge contacts are missed): no scene needs it.
// Plane and sdf are only ever the second shape of a pair (static scenery, the head); two of them
// never collide with each other (supported() says which pairs are measured).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

namespace ponyhop {

class SignedDistanceGrid;

enum class ShapeType { Sphere, Capsule, Box, Plane, Sdf };

struct Shape {
  ShapeType type = ShapeType::Sphere;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();              // in the body frame
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // shape to body
  double radius = 0.0;                                           // sphere
  double half_length = 0.0;                                      // capsule
  double radius_a = 0.0, radius_b = 0.0;                         // capsule ends (+z, -z)
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();        // box
  std::shared_ptr<const SignedDistanceGrid> sdf;                 // sdf (grid in the shape frame)

  static Shape sphere(double r, const Eigen::Vector3d& at = Eigen::Vector3d::Zero());
  static Shape capsule(double half_length, double r_a, double r_b, const Eigen::Vector3d& at = Eigen::Vector3d::Zero(),
                       const Eigen::Quaterniond& rot = Eigen::Quaterniond::Identity());
  static Shape box(const Eigen::Vector3d& half, const Eigen::Vector3d& at = Eigen::Vector3d::Zero(),
                   const Eigen::Quaterniond& rot = Eigen::Quaterniond::Identity());
  // The plane through `point` with outward normal `normal` (shape frame = body frame rotated).
  static Shape plane(const Eigen::Vector3d& normal, const Eigen::Vector3d& point = Eigen::Vector3d::Zero());
  static Shape grid(std::shared_ptr<const SignedDistanceGrid> g);

  bool rounded() const { return type == ShapeType::Sphere || type == ShapeType::Capsule; }
};

// A shape placed in the world: the body's pose times the shape's local pose.
struct PlacedShape {
  const Shape* shape = nullptr;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // shape frame to world
};
PlacedShape place(const Shape& shape, const Eigen::Vector3d& body_x, const Eigen::Quaterniond& body_q);

// One point of contact between shapes a and b.
struct ContactPoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    // world, midway between the surfaces
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, world, from b towards a
  double gap = 0.0;                                   // signed distance between the surfaces (< 0: overlap)
  // Where on the measured shape (a rounded shape's or a box's, whichever order the pair is
  // measured in): a core parameter s in [0, 1], or a box's corner index. measureAt() takes it.
  double feature = 0.0;
};

// Signed distance of the world point x to a placed shape (negative inside) and its gradient
// (the outward unit normal of the nearest surface point; for an sdf, of the interpolated field).
double signedDistance(const PlacedShape& s, const Eigen::Vector3d& x, Eigen::Vector3d* gradient = nullptr);

// Whether collide() measures the pair (a, b) in this order or the other.
bool supported(ShapeType a, ShapeType b);

// Appends the contacts between a and b whose gap is below `reach` (m; 0 = touching or
// overlapping only). Normals point from b towards a. A sphere gives one point; a capsule its
// deepest point first, then its end spheres when they too are within reach (a capsule lying on a
// surface rests on a segment); a box its corners (up to 8). Pairs that are only supported the other way round are
// swapped (and their normals turned). Returns the number appended.
// `queries`: when given, counts the signed-distance evaluations of b (the narrow phase's cost).
// `clearance`: for a rounded shape against a grid (either order) that has no contact within
// reach, the search goes on (after its answer is settled: the contacts found are the same) until
// every part of the core is bounded below by `clearance->certify` or by its closest samples, and
// `clearance->lower` gets a lower bound of the pair's smallest gap min_s D(p(s)) - r(s) over the
// whole core (the grid's interpolant; -infinity when there is none). A caller that keeps it can
// skip the pair while the core has moved too little to close it (Collisions::detect).
struct GridClearance {
  double certify = 0.0;  // m: search on to this gap (at most, where the grid's spacing allows)
  double lower = -std::numeric_limits<double>::infinity();
};
int collide(const PlacedShape& a, const PlacedShape& b, double reach, std::vector<ContactPoint>& out,
            long* queries = nullptr, GridClearance* clearance = nullptr);

// The contact collide(a, b) found at `feature` (ContactPoint::feature), measured again at the
// shapes' present poses without a search: one query with its gradient. The gap there is at least
// the pair's smallest, and equal to it to second order in how far the deepest point moved along
// the shape (the push-out's small moves: docs/PHYSICS.md, "Collisions").
ContactPoint measureAt(const PlacedShape& a, const PlacedShape& b, double feature, long* queries = nullptr);

// A lower bound of min_s D(p(s)) - r(s) over the core from a (radius ra) to b (radius rb), both in
// the grid's own frame: the grid's values at the two ends and its Lipschitz bound over the whole
// segment (the capsule search's first interval). The link's clearance, never overestimated; two
// queries.
double gridGapBound(const SignedDistanceGrid& g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ra,
                    double rb);

// Exact geometry used above and by the tests.
// The point of the triangle (p0, p1, p2) closest to x (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& x, const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                       const Eigen::Vector3d& p2);
// Minimum of a convex function on [lo, hi] by golden-section search; returns the argument.
// f(lo) and f(hi) when the caller has them already (NaN: evaluated here).
template <class F>
double minimizeConvex(F f, double lo, double hi, double tolerance = 1e-12,
                      double flo = std::numeric_limits<double>::quiet_NaN(),
                      double fhi = std::numeric_limits<double>::quiet_NaN()) {
  constexpr double kInvPhi = 0.6180339887498949;
  double a = lo, b = hi;
  double c = b - kInvPhi * (b - a), d = a + kInvPhi * (b - a);
  double fc = f(c), fd = f(d);
  while (b - a > tolerance) {
    if (fc <= fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - kInvPhi * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + kInvPhi * (b - a);
      fd = f(d);
    }
  }
  const double m = 0.5 * (a + b);
  // The ends are candidates too (a monotone f has its minimum there).
  const double fm = f(m);
  if (std::isnan(flo)) flo = f(lo);
  if (std::isnan(fhi)) fhi = f(hi);
  if (flo <= fm && flo <= fhi) return lo;
  if (fhi <= fm) return hi;
  return m;
}

}  // namespace ponyhop

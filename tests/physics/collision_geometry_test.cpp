// Collision geometry against analytic answers: signed distances, gaps, normals and contact points
// of every pair the scenes use (physics/shapes.h), and the mesh signed distance grid against the
// exact distance of spheres and boxes (physics/mesh_sdf.h), and the bucketed exact distance the
// head tests measure with against the brute force over every triangle (physics/triangle_distance.h).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <tuple>

#include "physics/mesh_sdf.h"
#include "physics/shapes.h"
#include "physics/triangle_distance.h"

namespace ponyhop {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;

const Quaterniond kIdentity = Quaterniond::Identity();

ContactPoint only(const Shape& a, const Vector3d& xa, const Quaterniond& qa, const Shape& b, const Vector3d& xb,
                  const Quaterniond& qb) {
  std::vector<ContactPoint> out;
  EXPECT_GE(collide(place(a, xa, qa), place(b, xb, qb), 1e9, out), 1);  // the deepest first
  return out.empty() ? ContactPoint{} : out.front();
}

TEST(CollisionGeometry, SphereOnPlane) {
  const Shape ball = Shape::sphere(0.1);
  const Shape ground = Shape::plane(Vector3d::UnitZ());
  const ContactPoint c = only(ball, Vector3d(0.3, -0.2, 0.25), kIdentity, ground, Vector3d::Zero(), kIdentity);
  EXPECT_NEAR(c.gap, 0.15, 1e-12);
  EXPECT_NEAR((c.normal - Vector3d::UnitZ()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((c.point - Vector3d(0.3, -0.2, 0.075)).norm(), 0.0, 1e-12);  // midway between 0.15 and 0
  // Overlapping: negative gap. The plane's order does not matter (the normal turns).
  std::vector<ContactPoint> out;
  collide(place(ground, Vector3d::Zero(), kIdentity), place(ball, Vector3d(0, 0, 0.04), kIdentity), 0.0, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(out[0].gap, -0.06, 1e-12);
  EXPECT_NEAR((out[0].normal + Vector3d::UnitZ()).norm(), 0.0, 1e-12);
}

TEST(CollisionGeometry, TiltedTaperedCapsuleOnPlaneTouchesAtItsLowestEnd) {
  // Half length 0.1, radius 0.03 at +z, 0.01 at -z, turned 60 deg about x.
  const double tilt = std::numbers::pi / 3.0;
  const Quaterniond q(Eigen::AngleAxisd(tilt, Vector3d::UnitX()));
  const Shape cap = Shape::capsule(0.1, 0.03, 0.01);
  const Shape ground = Shape::plane(Vector3d::UnitZ());
  const Vector3d centre(0, 0, 0.2);
  const ContactPoint c = only(cap, centre, q, ground, Vector3d::Zero(), kIdentity);
  const double z_top = 0.2 + 0.1 * std::cos(tilt), z_bottom = 0.2 - 0.1 * std::cos(tilt);
  EXPECT_NEAR(c.gap, std::min(z_top - 0.03, z_bottom - 0.01), 1e-10);
  EXPECT_NEAR((c.normal - Vector3d::UnitZ()).norm(), 0.0, 1e-12);
  // Tilted the other way the thick end is low: z - r is linear along the axis, so an end wins.
  const Quaterniond q2(Eigen::AngleAxisd(std::numbers::pi - tilt, Vector3d::UnitX()));
  const ContactPoint c2 = only(cap, centre, q2, ground, Vector3d::Zero(), kIdentity);
  EXPECT_NEAR(c2.gap, z_bottom - 0.03, 1e-10);
}

TEST(CollisionGeometry, SkewCapsulesMeetAtTheCommonPerpendicular) {
  // Capsule a along x at z = 0.05, capsule b along y at z = 0: distance between axes 0.05.
  const Quaterniond along_x = rotationBetween(Vector3d::UnitZ(), Vector3d::UnitX());
  const Quaterniond along_y = rotationBetween(Vector3d::UnitZ(), Vector3d::UnitY());
  const Shape a = Shape::capsule(0.2, 0.01, 0.01);
  const Shape b = Shape::capsule(0.2, 0.015, 0.015);
  const ContactPoint c = only(a, Vector3d(0.02, 0, 0.05), along_x, b, Vector3d(0, -0.03, 0), along_y);
  EXPECT_NEAR(c.gap, 0.05 - 0.025, 1e-9);
  EXPECT_NEAR((c.normal - Vector3d::UnitZ()).norm(), 0.0, 1e-6);
  // Surfaces at z = 0.04 (a) and 0.015 (b): the point midway.
  EXPECT_NEAR((c.point - Vector3d(0, 0, 0.0275)).norm(), 0.0, 1e-6);
  // Parallel, overlapping: the gap is the axis distance minus the radii.
  const ContactPoint p = only(a, Vector3d(0, 0, 0.02), along_x, b, Vector3d(0.05, 0, 0), along_x);
  EXPECT_NEAR(p.gap, 0.02 - 0.025, 1e-9);
}

TEST(CollisionGeometry, TaperedCapsuleAgainstSphereMatchesDenseSampling) {
  const Shape cap = Shape::capsule(0.05, 0.02, 0.005);
  const Shape ball = Shape::sphere(0.03);
  const Quaterniond q(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  for (int trial = 0; trial < 50; ++trial) {
    const Vector3d centre(u(rng), u(rng), u(rng));
    const ContactPoint c = only(cap, Vector3d::Zero(), q, ball, centre, kIdentity);
    // Reference: the round cone's distance as the minimum over 200001 spheres along the axis.
    double ref = 1e9;
    for (int i = 0; i <= 200000; ++i) {
      const double s = i / 200000.0;
      const Vector3d p = q * Vector3d(0, 0, 0.05 - 0.1 * s);
      ref = std::min(ref, (centre - p).norm() - 0.03 - (0.02 + s * (0.005 - 0.02)));
    }
    EXPECT_NEAR(c.gap, ref, 1e-9) << trial;
    // The normal points from the sphere to the capsule's core point.
    EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12);
  }
}

TEST(CollisionGeometry, BoxSignedDistanceInsideAndOutside) {
  const Shape box = Shape::box(Vector3d(0.1, 0.2, 0.3));
  const PlacedShape p =
      place(box, Vector3d(1, 0, 0), Quaterniond(Eigen::AngleAxisd(0.5 * std::numbers::pi, Vector3d::UnitZ())));
  // The box turned 90 deg about z: its x half extent lies along world y.
  Vector3d g;
  EXPECT_NEAR(signedDistance(p, Vector3d(1, 0.15, 0), &g), 0.05, 1e-12);
  EXPECT_NEAR((g - Vector3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(signedDistance(p, Vector3d(1, 0, 0), &g), -0.1, 1e-12);  // nearest face: x half extent
  EXPECT_NEAR(signedDistance(p, Vector3d(1 + 0.2 + 0.03, 0.1 + 0.04, 0), &g), 0.05, 1e-12);  // edge region
}

TEST(CollisionGeometry, BoxRestingOnAPlaneTouchesAtItsFourLowerCorners) {
  const Shape box = Shape::box(Vector3d(0.1, 0.1, 0.05));
  const Shape ground = Shape::plane(Vector3d::UnitZ());
  std::vector<ContactPoint> out;
  collide(place(box, Vector3d(0, 0, 0.05 - 1e-4), kIdentity), place(ground, Vector3d::Zero(), kIdentity), 0.0, out);
  ASSERT_EQ(out.size(), 4u);
  for (const ContactPoint& c : out) {
    EXPECT_NEAR(c.gap, -1e-4, 1e-12);
    EXPECT_NEAR(std::abs(c.point.x()), 0.1, 1e-12);
  }
  // A sphere in a box's corner region: distance to the corner.
  const ContactPoint s =
      only(Shape::sphere(0.01), Vector3d(0.13, 0.14, 0.05), kIdentity, box, Vector3d::Zero(), kIdentity);
  EXPECT_NEAR(s.gap, std::hypot(0.03, 0.04) - 0.01, 1e-12);
}

TEST(CollisionGeometry, ClosestPointOnTriangleInEveryRegion) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_NEAR((closestPointOnTriangle(Vector3d(0.2, 0.2, 0.5), a, b, c) - Vector3d(0.2, 0.2, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((closestPointOnTriangle(Vector3d(-1, -1, 0), a, b, c) - a).norm(), 0, 1e-15);
  EXPECT_NEAR((closestPointOnTriangle(Vector3d(2, -1, 0), a, b, c) - b).norm(), 0, 1e-15);
  EXPECT_NEAR((closestPointOnTriangle(Vector3d(0.5, -1, 0), a, b, c) - Vector3d(0.5, 0, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((closestPointOnTriangle(Vector3d(1, 1, 0), a, b, c) - Vector3d(0.5, 0.5, 0)).norm(), 0, 1e-15);
}

// An icosphere (subdivided icosahedron projected onto the sphere), outward winding.
void icosphere(double radius, int levels, std::vector<Vector3d>& v, std::vector<uint32_t>& idx) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
       {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  idx = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
         3, 9,  4, 3, 4, 2, 3, 2, 6, 3, 6, 8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::vector<uint32_t> next;
    for (size_t i = 0; i < idx.size(); i += 3) {
      const uint32_t a = idx[i], b = idx[i + 1], c = idx[i + 2];
      const auto mid = [&](uint32_t x, uint32_t y) {
        v.push_back((v[x] + v[y]).normalized());
        return static_cast<uint32_t>(v.size() - 1);
      };
      const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    idx = next;
  }
  for (auto& p : v) p *= radius;
}

TEST(MeshSdf, SphereMeshFieldMatchesTheTrianglesNearTheSurface) {
  std::vector<Vector3d> v;
  std::vector<uint32_t> idx;
  icosphere(0.1, 4, v, idx);  // 5120 triangles
  SignedDistanceGrid g;
  const Status built = g.build(v, idx, 0.004, 0.02);
  ASSERT_TRUE(built.ok()) << built.message();
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> r(0.08, 0.12);
  double worst = 0.0;
  for (int i = 0; i < 300; ++i) {
    const Vector3d p = Vector3d(n(rng), n(rng), n(rng)).normalized() * r(rng);
    const double exact = signedDistanceToTriangles(v, idx, p);
    worst = std::max(worst, std::abs(g.distance(p) - exact));
    // The interpolated field's gradient is close to the radial direction.
    EXPECT_GT(g.gradient(p).dot(p.normalized()), 0.98);
  }
  // Trilinear error on a smooth surface: O(cell^2 / radius) = 1.6e-4 m here.
  EXPECT_LT(worst, 2e-4);
  // The sign far inside and outside.
  EXPECT_LT(g.distance(Vector3d::Zero()), -0.09);
  EXPECT_GT(g.distance(Vector3d(0.2, 0.2, 0.2)), 0.2);
}

TEST(MeshSdf, BoxMeshFieldIsExactOnFacesAndBoundedAtEdges) {
  // A box as 12 triangles.
  const std::vector<Vector3d> v = {{-0.1, -0.05, -0.08}, {0.1, -0.05, -0.08}, {0.1, 0.05, -0.08}, {-0.1, 0.05, -0.08},
                                   {-0.1, -0.05, 0.08},  {0.1, -0.05, 0.08},  {0.1, 0.05, 0.08},  {-0.1, 0.05, 0.08}};
  const std::vector<uint32_t> idx = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                     1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  SignedDistanceGrid g;
  const Status built = g.build(v, idx, 0.005, 0.02);
  ASSERT_TRUE(built.ok()) << built.message();
  const Shape exact = Shape::box(Vector3d(0.1, 0.05, 0.08));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.13, 0.13);
  double worst_face = 0.0, worst = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p(u(rng), u(rng), u(rng));
    const double ref = signedDistance(place(exact, Vector3d::Zero(), kIdentity), p);
    if (std::abs(ref) > 0.01) continue;
    const double err_here = std::abs(g.distance(p) - ref);
    worst = std::max(worst, err_here);
    // Away from edges (more than a cell from any other face) trilinear is exact for a plane.
    const Vector3d q = Vector3d(0.1, 0.05, 0.08) - p.cwiseAbs();
    std::array<double, 3> c{q.x(), q.y(), q.z()};
    std::sort(c.begin(), c.end());
    if (c[1] > 0.011) worst_face = std::max(worst_face, err_here);
  }
  EXPECT_LT(worst_face, 1e-6);    // float storage
  EXPECT_LT(worst, 0.3 * 0.005);  // at edges and corners: a fraction of a cell
  const Status empty = g.build(v, {}, 0.005, 0.0);
  EXPECT_FALSE(empty.ok());
  EXPECT_NE(empty.message().find("no triangles"), std::string::npos);
}

TEST(MeshSdf, CapsuleAgainstTheGridFindsTheDeepestPointAlongTheLink) {
  std::vector<Vector3d> v;
  std::vector<uint32_t> idx;
  icosphere(0.1, 4, v, idx);
  auto g = std::make_shared<SignedDistanceGrid>();
  const Status built = g->build(v, idx, 0.004, 0.03);
  ASSERT_TRUE(built.ok()) << built.message();
  const Shape head = Shape::grid(g);
  const Shape head_exact = Shape::sphere(0.1);
  // A horizontal capsule across the top of the sphere, tapered.
  const Quaterniond along_x = rotationBetween(Vector3d::UnitZ(), Vector3d::UnitX());
  const Shape cap = Shape::capsule(0.03, 0.012, 0.006);
  for (double z : {0.105, 0.11, 0.12}) {
    const ContactPoint c = only(cap, Vector3d(0.01, 0, z), along_x, head, Vector3d::Zero(), kIdentity);
    const ContactPoint e = only(cap, Vector3d(0.01, 0, z), along_x, head_exact, Vector3d::Zero(), kIdentity);
    // The mesh lies inside the sphere by at most its faceting (~0.3 mm at this level).
    EXPECT_NEAR(c.gap, e.gap, 6e-4) << z;
    EXPECT_GT(c.normal.dot(e.normal), 0.99) << z;
  }
}

// measureAt() gives back the contact collide() found at its feature (the push-out's re-measure
// against a grid, physics/collisions.h): at the same poses the same point, normal and gap; moved
// 1 mm away along the normal, the gap 1 mm larger. A box's corners, a tilted capsule against a
// plane in either order (the normal turned), and a capsule against a grid.
TEST(CollisionGeometry, MeasureAtRepeatsTheContactAtItsFeature) {
  std::vector<Vector3d> v;
  std::vector<uint32_t> idx;
  icosphere(0.1, 3, v, idx);
  auto g = std::make_shared<SignedDistanceGrid>();
  ASSERT_TRUE(g->build(v, idx, 0.004, 0.03).ok());
  const Shape ground = Shape::plane(Vector3d::UnitZ()), head = Shape::grid(g);
  const Shape box = Shape::box(Vector3d(0.1, 0.1, 0.05)), cap = Shape::capsule(0.05, 0.02, 0.01);
  const Quaterniond tilt(Eigen::AngleAxisd(0.3, Vector3d(1, 1, 0).normalized()));
  const Quaterniond along_x = rotationBetween(Vector3d::UnitZ(), Vector3d::UnitX());
  struct Case {
    const Shape *a, *b;
    Vector3d xa;
    Quaterniond qa;
    Vector3d away;  // a's move that opens every contact by 1 mm
  };
  const Case cases[] = {
      {&box, &ground, Vector3d(0, 0, 0.05 - 1e-4), tilt, Vector3d(0, 0, 1e-3)},
      {&cap, &ground, Vector3d(0, 0, 0.03), tilt, Vector3d(0, 0, 1e-3)},
      {&ground, &cap, Vector3d::Zero(), kIdentity, Vector3d(0, 0, -1e-3)},
      {&cap, &head, Vector3d(0.01, 0, 0.115), along_x, Vector3d(0, 0, 1e-3)},
  };
  for (const Case& c : cases) {
    const bool swapped = c.a == &ground;
    const Vector3d xb = swapped ? Vector3d(0, 0, 0.03) : Vector3d::Zero();
    const Quaterniond qb = swapped ? tilt : kIdentity;
    std::vector<ContactPoint> out;
    ASSERT_GE(collide(place(*c.a, c.xa, c.qa), place(*c.b, xb, qb), 1e-3, out), 1);
    for (const ContactPoint& found : out) {
      const ContactPoint same = measureAt(place(*c.a, c.xa, c.qa), place(*c.b, xb, qb), found.feature);
      EXPECT_EQ(same.gap, found.gap);
      EXPECT_EQ(same.normal, found.normal);
      EXPECT_EQ(same.point, found.point);
      // Along z the grid's interpolant is exact to its cell's curvature error (4 mm cells, r = 0.1).
      const ContactPoint moved = measureAt(place(*c.a, c.xa + c.away, c.qa), place(*c.b, xb, qb), found.feature);
      EXPECT_NEAR(moved.gap, found.gap + 1e-3 * std::abs(found.normal.z()), c.b == &head ? 1e-4 : 1e-12);
    }
  }
}

// The bucketed query gives the brute force's answer: the same distance within its reach (the same
// closest-point code over a subset that holds the nearest triangle), a value at least the reach
// beyond it, and the same sign everywhere, inside and out, near and far. On a fine sphere (small
// triangles in many buckets) and a box of 12 large triangles (each over thousands of buckets).
TEST(MeshSdf, BucketedTriangleDistanceIsTheBruteForce) {
  std::vector<Vector3d> sphere;
  std::vector<uint32_t> sphere_idx;
  icosphere(0.1, 3, sphere, sphere_idx);
  const std::vector<Vector3d> box = {{-0.4, -0.5, -0.45}, {0.4, -0.5, -0.45}, {0.4, 0.5, -0.45}, {-0.4, 0.5, -0.45},
                                     {-0.4, -0.5, 0.45},  {0.4, -0.5, 0.45},  {0.4, 0.5, 0.45},  {-0.4, 0.5, 0.45}};
  const std::vector<uint32_t> box_idx = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                         1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  const double reach = 0.015;
  for (const auto& [v, idx, size] : {std::tuple{sphere, sphere_idx, 0.1}, std::tuple{box, box_idx, 0.5}}) {
    const TriangleDistance fast(v, idx, 0.01, reach);
    std::mt19937 rng(5);
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> r(0.0, 1.3 * size);
    int near = 0, inside = 0;
    for (int i = 0; i < 3000; ++i) {
      // Half the points within a few reaches of the surface, half anywhere in and around it.
      const Vector3d dir = Vector3d(n(rng), n(rng), n(rng)).normalized();
      const Vector3d p = i % 2 == 0 ? dir * (size + 0.03 * n(rng)) : dir * r(rng);
      const double exact = signedDistanceToTriangles(v, idx, p);
      const double d = fast.signedDistance(p);
      ASSERT_EQ(d < 0.0, exact < 0.0) << p.transpose();
      if (std::abs(exact) < reach) {
        ASSERT_EQ(d, exact) << p.transpose();
        ++near;
      } else {
        ASSERT_GE(std::abs(d), reach) << p.transpose();
      }
      inside += exact < 0.0;
    }
    EXPECT_GT(near, 200);  // the comparison covered the surface, inside and out
    EXPECT_GT(inside, 300);
  }
}

}  // namespace
}  // namespace ponyhop

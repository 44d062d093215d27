// The ponytail dressed as hair (engine/hair.h): the drawn surface follows a smooth curve through
// the joints however sharply the chain bends, and the strands spread toward the tip.
#include "engine/hair.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>

#include "engine/render_session.h"
#include "sim/scene_io.h"

using namespace ponyhop;

namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * kDeg;
}

// A chain of `bends.size() + 1` links of length L, each turning by bends[i] degrees from the one
// before it, alternately about x and about y (a 3D zigzag).
std::vector<Eigen::Vector3d> bentChain(const std::vector<double>& bends, double L = 0.028) {
  std::vector<Eigen::Vector3d> p{Eigen::Vector3d::Zero()};
  Eigen::Vector3d dir(0.0, 0.0, -1.0);
  p.push_back(p.back() + L * dir);
  for (size_t i = 0; i < bends.size(); ++i) {
    const Eigen::Vector3d axis = i % 2 == 0 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    dir = Eigen::AngleAxisd(bends[i] / kDeg, axis) * dir;
    p.push_back(p.back() + L * dir);
  }
  return p;
}

std::vector<double> taperedRadii(size_t n) {
  std::vector<double> r;
  for (size_t i = 0; i < n; ++i) r.push_back(0.014 * (1.0 - 0.6 * double(i) / double(n - 1)));
  return r;
}

// The largest change of a surface normal between the ring of a joint and its neighbouring rings,
// over every joint and every point around the tube.
double largestNormalTurnAtJoints(const HairCurve& c, int sides) {
  std::vector<Eigen::Vector3d> pos, nrm;
  hairTube(c, 1.0, sides, pos, nrm);
  double worst = 0.0;
  for (size_t j = 1; j + 1 < c.joint_samples.size(); ++j) {  // the interior joints
    const size_t ring = size_t(c.joint_samples[j]);
    for (size_t k = 0; k < size_t(sides); ++k) {
      const Eigen::Vector3d& n = nrm[ring * size_t(sides) + k];
      worst = std::max(worst, angleDeg(nrm[(ring - 1) * size_t(sides) + k], n));
      worst = std::max(worst, angleDeg(n, nrm[(ring + 1) * size_t(sides) + k]));
    }
  }
  return worst;
}

TEST(Hair, CurvePassesThroughEveryJoint) {
  const auto pts = bentChain({40.0, -70.0, 90.0, 30.0});
  const HairCurve c = hairCurve(pts, taperedRadii(pts.size()), Eigen::Vector3d::UnitX(), 6);
  ASSERT_EQ(c.joint_samples.size(), pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    EXPECT_LT((c.points[size_t(c.joint_samples[i])] - pts[i]).norm(), 1e-12) << "joint " << i;
    EXPECT_NEAR(c.radius[size_t(c.joint_samples[i])], taperedRadii(pts.size())[i], 1e-12);
  }
  for (size_t i = 0; i < c.points.size(); ++i) {
    EXPECT_NEAR(c.tangents[i].norm(), 1.0, 1e-9);
    EXPECT_NEAR(c.normals[i].norm(), 1.0, 1e-9);
    EXPECT_NEAR(c.normals[i].dot(c.tangents[i]), 0.0, 1e-9) << "frames stay perpendicular";
  }
}

// The kink test: bend a chain sharply (each joint 70 to 120 degrees, in alternating planes) and
// measure how far the drawn surface's normals turn from a joint's ring to its neighbours. A
// surface made of straight pieces (capsules, or a polyline tube) turns by the whole bend angle at
// the joint, however finely it is sampled; a smooth surface turns less and less as the sampling
// gets finer (the normals are continuous across the joint).
TEST(Hair, SharplyBentChainHasNoKinkAtAnyJoint) {
  const std::vector<double> bends{90.0, -120.0, 70.0, 110.0, -90.0, 120.0, 80.0};
  const auto pts = bentChain(bends);
  const auto radii = taperedRadii(pts.size());
  const double coarse = largestNormalTurnAtJoints(hairCurve(pts, radii, Eigen::Vector3d::UnitX(), 16), 16);
  const double fine = largestNormalTurnAtJoints(hairCurve(pts, radii, Eigen::Vector3d::UnitX(), 64), 16);
  const double finer = largestNormalTurnAtJoints(hairCurve(pts, radii, Eigen::Vector3d::UnitX(), 256), 16);
  EXPECT_LT(fine, 0.6 * coarse) << "the turn at a joint shrinks with the sampling: " << coarse << " -> " << fine;
  EXPECT_LT(finer, 0.6 * fine) << fine << " -> " << finer;
  EXPECT_LT(finer, 5.0) << "degrees: no crease at the joints (the bends are 70 to 120 degrees)";
}

// The curve's own tangent is continuous across the joints too (a kink-free centre line).
TEST(Hair, TangentIsContinuousAcrossJoints) {
  const auto pts = bentChain({120.0, -120.0, 120.0, 90.0});
  const HairCurve c = hairCurve(pts, taperedRadii(pts.size()), Eigen::Vector3d::UnitX(), 256);
  for (size_t j = 1; j + 1 < c.joint_samples.size(); ++j) {
    const size_t i = size_t(c.joint_samples[j]);
    EXPECT_LT(angleDeg(c.tangents[i - 1], c.tangents[i]), 3.0) << "joint " << j;
    EXPECT_LT(angleDeg(c.tangents[i], c.tangents[i + 1]), 3.0) << "joint " << j;
  }
}

// The strands of a bent tail: each strand's drawn direction is continuous too. (A strand offset
// from the centre by more than the bend's radius of curvature folds back; the bends here are as
// tight as the default tail's links make when it whips: 60 degrees at 2.8 cm links.)
TEST(Hair, StrandsBendSmoothlyAcrossJoints) {
  const auto pts = bentChain({60.0, -60.0, 45.0, 60.0});
  HairParams hair;
  hair.noise = 0.0;
  const HairCurve c = hairCurve(pts, taperedRadii(pts.size()), Eigen::Vector3d::UnitX(), 128);
  const HairMesh m = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), 40);
  double worst = 0.0;
  for (size_t i = 2; i < m.vertices.size(); ++i) {
    const HairVertex &a = m.vertices[i - 2], &b = m.vertices[i];
    if (a.half_width == 0.0f || b.half_width == 0.0f) continue;  // the tube
    const Eigen::Vector3d ta(a.tangent[0], a.tangent[1], a.tangent[2]), tb(b.tangent[0], b.tangent[1], b.tangent[2]);
    const Eigen::Vector3d pa(a.pos[0], a.pos[1], a.pos[2]), pb(b.pos[0], b.pos[1], b.pos[2]);
    if ((pa - pb).norm() > 0.003) continue;  // the next strand starts here
    worst = std::max(worst, angleDeg(ta, tb));
  }
  EXPECT_LT(worst, 8.0) << "degrees between neighbouring strand samples";
}

double clumpRadius(const HairMesh& m, const HairCurve& c, size_t sample) {
  double r = 0.0;
  for (const HairVertex& v : m.vertices) {
    if (v.half_width == 0.0f) continue;
    const Eigen::Vector3d p(v.pos[0], v.pos[1], v.pos[2]);
    if ((p - c.points[sample]).dot(c.tangents[sample]) > 1e-4 || (p - c.points[sample]).dot(c.tangents[sample]) < -1e-4)
      continue;
    r = std::max(r, (p - c.points[sample]).norm());
  }
  return r;
}

TEST(Hair, StrandsSpreadTowardTheTipAndFollowTheKnobs) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i <= 8; ++i) pts.push_back(Eigen::Vector3d(0.0, 0.0, -0.03 * i));
  const std::vector<double> radii(pts.size(), 0.01);
  const HairCurve c = hairCurve(pts, radii, Eigen::Vector3d::UnitX(), 6);
  HairParams hair;
  hair.noise = 0.0;
  hair.spread = 2.0;
  const HairMesh m = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), 200);
  EXPECT_EQ(m.strands, 200u);
  const size_t root = 0, near_tip = c.points.size() * 3 / 4;
  const double r_root = clumpRadius(m, c, root), r_tip = clumpRadius(m, c, near_tip);
  EXPECT_NEAR(r_root, 0.0095, 0.001) << "tied at the root";
  const double s = c.s[near_tip];
  EXPECT_NEAR(r_tip, 0.0095 * (1.0 + 2.0 * s * s), 0.0015) << "wider toward the tip";
  hair.spread = 0.0;
  const HairMesh narrow = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), 200);
  EXPECT_NEAR(clumpRadius(narrow, c, near_tip), r_root, 0.001) << "spread 0: the clump keeps the links' radius";
  // Colour variation: strands differ; none with variation 0.
  hair.color_variation = 0.0;
  const HairMesh plain = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), 50);
  const auto redRange = [](const HairMesh& mesh) {
    float lo = 1e9f, hi = -1e9f;
    for (const HairVertex& v : mesh.vertices) {
      if (v.half_width == 0.0f) continue;
      lo = std::min(lo, v.color[0]);
      hi = std::max(hi, v.color[0]);
    }
    return hi / lo;
  };
  EXPECT_FLOAT_EQ(redRange(plain), 1.0f);
  EXPECT_GT(redRange(m), 1.15f) << "per-strand colour variation";
}

TEST(Hair, DraftDrawsFewerStrandsAndTheMeshIsDeterministic) {
  HairParams hair;
  EXPECT_EQ(hairStrandCount(hair, false), hair.strands);
  EXPECT_EQ(hairStrandCount(hair, true), hair.strands_draft);
  EXPECT_LT(hairStrandCount(hair, true), hairStrandCount(hair, false));
  const auto pts = bentChain({30.0, 20.0, -40.0});
  const HairCurve c = hairCurve(pts, taperedRadii(pts.size()), Eigen::Vector3d::UnitX());
  const HairMesh a = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), hairStrandCount(hair, true));
  const HairMesh b = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), hairStrandCount(hair, true));
  const HairMesh full = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), hairStrandCount(hair, false));
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  EXPECT_EQ(0, std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(HairVertex)));
  EXPECT_LT(a.indices.size(), full.indices.size());
}

// The shadow pass's triangles: fewer, through the samples of each strand and of the tube it keeps,
// from root to tip; the samples it leaves out lie within kShadowChordTolerance strand widths of
// the chords that replace them.
TEST(Hair, ShadowTrianglesLeaveOutOnlySamplesNearTheirChords) {
  HairParams hair;
  const auto pts = bentChain({30.0, 20.0, -40.0});
  const HairCurve c = hairCurve(pts, taperedRadii(pts.size()), Eigen::Vector3d::UnitX());
  const HairMesh m = buildHair(c, hair, Eigen::Vector3f(0.4f, 0.25f, 0.1f), hairStrandCount(hair, false));
  ASSERT_FALSE(m.shadow_indices.empty());
  ASSERT_EQ(m.shadow_indices.size() % 3, 0u);
  const double share = double(m.shadow_indices.size()) / double(m.indices.size());
  EXPECT_LT(share, 0.8) << "the shadow pass keeps nearly every sample";
  EXPECT_GT(share, 0.2);
  std::vector<char> used(m.vertices.size(), 0), used_main(m.vertices.size(), 0);
  for (uint32_t i : m.indices) used_main[i] = 1;
  for (uint32_t i : m.shadow_indices) {
    ASSERT_LT(i, m.vertices.size());
    EXPECT_TRUE(used_main[i]) << "vertex " << i << " is in the shadow pass only";
    used[i] = 1;
  }
  // The tube (the first vertices, 12 a ring): its first and last rings.
  const size_t rings = c.points.size(), sides = 12;
  for (size_t k = 0; k < sides; ++k) {
    EXPECT_TRUE(used[k]);
    EXPECT_TRUE(used[(rings - 1) * sides + k]);
  }
  // The strands: vertex pairs from the root, where the half width is hair.width / 2, to the tip.
  const float root_hw = float(0.5 * hair.width);
  size_t roots = 0, tips = 0;
  for (size_t v = rings * sides; v < m.vertices.size();) {
    ASSERT_FLOAT_EQ(std::abs(m.vertices[v].half_width), root_hw) << "not a strand's root: " << v;
    size_t e = v + 2;
    while (e < m.vertices.size() && std::abs(m.vertices[e].half_width) != root_hw) e += 2;
    ++roots;
    EXPECT_TRUE(used[v] && used[v + 1]) << "a strand's root is not in the shadow pass";
    if (used[e - 1] && used[e - 2]) ++tips;
    // Each run of left-out samples lies within the tolerance of the chord between the kept ones
    // around it.
    const double tol = kShadowChordTolerance * hair.width + 1e-7;
    for (size_t a = v; a + 2 < e;) {
      size_t b = a + 2;
      while (!used[b]) b += 2;
      const Eigen::Vector3d pa = Eigen::Vector3f(m.vertices[a].pos).cast<double>();
      const Eigen::Vector3d u = (Eigen::Vector3f(m.vertices[b].pos).cast<double>() - pa).normalized();
      for (size_t q = a + 2; q < b; q += 2) {
        const Eigen::Vector3d d = Eigen::Vector3f(m.vertices[q].pos).cast<double>() - pa;
        EXPECT_LE((d - d.dot(u) * u).norm(), tol) << "strand vertex " << q;
      }
      a = b;
    }
    v = e;
  }
  EXPECT_EQ(roots, size_t(hairStrandCount(hair, false)));
  EXPECT_EQ(tips, roots) << "a strand's tip is not in the shadow pass";
}

// A render in draft quality (render.quality, or the window while the view moves) draws the draft
// strand count: fewer triangles than final.
TEST(Hair, DraftQualityRendersFewerStrands) {
  size_t triangles[2] = {0, 0};
  for (const int draft : {0, 1}) {
    Scene scene = loadScene("assets/scenes/ponytail.json", {{"render.quality", draft ? "draft" : "final"}});
    scene.render.width = 160;
    scene.render.height = 90;
    RenderSession session(scene);
    std::vector<uint8_t> rgba;
    session.renderFrame(0.0, rgba);
    triangles[draft] = session.stats().triangles;
  }
  EXPECT_LT(triangles[1], triangles[0]) << "draft " << triangles[1] << ", final " << triangles[0];
}

}  // namespace

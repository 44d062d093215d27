#include "engine/hair.h"

#include <algorithm>
#include <cmath>

#include "engine/color.h"

namespace ponyhop {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A point of the spline with its radius as a fourth coordinate (both follow the same knots).
using P4 = Eigen::Vector4d;

// Centripetal Catmull-Rom on the span p1 -> p2 (Barry-Goldman's pyramid) at knot t in [t1, t2],
// with its derivative d/dt (differentiated level by level). The knots are cumulative square roots
// of the chord lengths (alpha = 1/2): no cusps and no loops within a span, and the derivative at
// a shared point is the same from both spans (C1 in t: the drawn surface has no kink).
void catmullRom(const P4& p0, const P4& p1, const P4& p2, const P4& p3, double t0, double t1, double t2, double t3,
                double t, P4& value, P4& deriv) {
  const auto lerp = [](const P4& a, const P4& b, double ta, double tb, double tt, const P4& da, const P4& db, P4& out,
                       P4& dout) {
    const double w = tb - ta;
    out = ((tb - tt) * a + (tt - ta) * b) / w;
    dout = (b - a) / w + ((tb - tt) * da + (tt - ta) * db) / w;
  };
  const P4 zero = P4::Zero();
  P4 a1, a2, a3, da1, da2, da3, b1, b2, db1, db2;
  lerp(p0, p1, t0, t1, t, zero, zero, a1, da1);
  lerp(p1, p2, t1, t2, t, zero, zero, a2, da2);
  lerp(p2, p3, t2, t3, t, zero, zero, a3, da3);
  lerp(a1, a2, t0, t2, t, da1, da2, b1, db1);
  lerp(a2, a3, t1, t3, t, da2, da3, b2, db2);
  lerp(b1, b2, t1, t2, t, db1, db2, value, deriv);
}

Eigen::Vector3d perpendicular(const Eigen::Vector3d& t, const Eigen::Vector3d& hint) {
  Eigen::Vector3d n = hint - hint.dot(t) * t;
  if (n.norm() < 1e-6) {
    const Eigen::Vector3d other = std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    n = other - other.dot(t) * t;
  }
  return n.normalized();
}

// Deterministic per-strand random numbers in [0, 1) (integer hash, no global state).
double hash01(uint32_t a, uint32_t b) {
  uint32_t h = a * 0x9E3779B1u ^ (b + 0x7F4A7C15u) * 0x85EBCA77u;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return double(h >> 8) / double(1u << 24);
}

void put(float out[3], const Eigen::Vector3d& v) {
  out[0] = float(v.x());
  out[1] = float(v.y());
  out[2] = float(v.z());
}

// Core tube radius over the curve's radius: full at the root, closing to a point at the tip (a
// smooth function of s, so the tube's normals stay continuous).
double coreScale(double s) { return 0.8 * (1.0 - s * s * s * s); }
double coreScaleSlope(double s) { return -3.2 * s * s * s; }

}  // namespace

HairCurve hairCurve(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& radii,
                    const Eigen::Vector3d& reference, int per_segment) {
  HairCurve c;
  const size_t n = points.size();
  if (n < 2 || radii.size() != n) return c;
  per_segment = std::max(per_segment, 1);
  // Control points, with one phantom point mirrored past each end (a natural end tangent).
  std::vector<P4> p(n + 2);
  for (size_t i = 0; i < n; ++i) p[i + 1] << points[i], radii[i];
  p[0] = 2.0 * p[1] - p[2];
  p[n + 1] = 2.0 * p[n] - p[n - 1];
  std::vector<double> knot(n + 2, 0.0);
  for (size_t i = 1; i < n + 2; ++i) {
    const double chord = (p[i].head<3>() - p[i - 1].head<3>()).norm();
    knot[i] = knot[i - 1] + std::sqrt(std::max(chord, 1e-9));
  }
  std::vector<Eigen::Vector3d> derivs;
  for (size_t span = 0; span + 1 < n; ++span) {
    const size_t i = span + 1;  // the span runs p[i] -> p[i + 1]
    const int count = per_segment + (span + 2 == n ? 1 : 0);
    c.joint_samples.push_back(int(c.points.size()));
    for (int k = 0; k < count; ++k) {
      const double t = knot[i] + (knot[i + 1] - knot[i]) * double(k) / double(per_segment);
      P4 v, d;
      catmullRom(p[i - 1], p[i], p[i + 1], p[i + 2], knot[i - 1], knot[i], knot[i + 1], knot[i + 2], t, v, d);
      c.points.push_back(v.head<3>());
      c.radius.push_back(std::max(v.w(), 0.0));
      const double speed = std::max(d.head<3>().norm(), 1e-12);
      derivs.push_back(d.head<3>() / speed);
      c.dradius.push_back(d.w() / speed);
    }
  }
  c.joint_samples.push_back(int(c.points.size()) - 1);
  c.tangents = derivs;
  // Arc length by the dense polyline.
  const size_t m = c.points.size();
  c.s.assign(m, 0.0);
  for (size_t i = 1; i < m; ++i) c.s[i] = c.s[i - 1] + (c.points[i] - c.points[i - 1]).norm();
  c.length = c.s.back();
  if (c.length > 0.0)
    for (double& s : c.s) s /= c.length;
  // Rotation-minimizing frames by double reflection.
  c.normals.resize(m);
  c.normals[0] = perpendicular(c.tangents[0], reference);
  for (size_t i = 0; i + 1 < m; ++i) {
    const Eigen::Vector3d v1 = c.points[i + 1] - c.points[i];
    const double c1 = v1.squaredNorm();
    Eigen::Vector3d r = c.normals[i], t = c.tangents[i];
    if (c1 > 1e-20) {
      r -= (2.0 / c1) * v1.dot(r) * v1;
      t -= (2.0 / c1) * v1.dot(t) * v1;
    }
    const Eigen::Vector3d v2 = c.tangents[i + 1] - t;
    const double c2 = v2.squaredNorm();
    if (c2 > 1e-20) r -= (2.0 / c2) * v2.dot(r) * v2;
    c.normals[i + 1] = perpendicular(c.tangents[i + 1], r);
  }
  return c;
}

int hairStrandCount(const HairParams& hair, bool draft) {
  return std::max(0, draft ? std::min(hair.strands_draft, hair.strands) : hair.strands);
}

void hairTube(const HairCurve& curve, double radius_scale, int sides, std::vector<Eigen::Vector3d>& positions,
              std::vector<Eigen::Vector3d>& normals) {
  positions.clear();
  normals.clear();
  sides = std::max(sides, 3);
  for (size_t i = 0; i < curve.points.size(); ++i) {
    const double s = curve.s[i];
    const double R = radius_scale * coreScale(s) * curve.radius[i];
    // d R / d arc length: the tube's side leans by it, so the normal tilts toward the root.
    const double slope = radius_scale * (coreScaleSlope(s) / std::max(curve.length, 1e-9) * curve.radius[i] +
                                         coreScale(s) * curve.dradius[i]);
    const Eigen::Vector3d u = curve.normals[i], v = curve.binormal(i), t = curve.tangents[i];
    for (int k = 0; k < sides; ++k) {
      const double a = 2.0 * kPi * double(k) / double(sides);
      const Eigen::Vector3d radial = std::cos(a) * u + std::sin(a) * v;
      positions.push_back(curve.points[i] + R * radial);
      normals.push_back((radial - slope * t).normalized());
    }
  }
}

HairMesh buildHair(const HairCurve& curve, const HairParams& hair, const Eigen::Vector3f& color, int strands,
                   int tube_sides) {
  HairMesh mesh;
  mesh.shading.highlight = float(hair.highlight);
  mesh.shading.shift = float(hair.highlight_shift);
  const size_t m = curve.points.size();
  if (m < 3) return mesh;
  const Eigen::Vector3d albedo(float(srgbToLinear(color.x())), float(srgbToLinear(color.y())),
                               float(srgbToLinear(color.z())));

  // The core tube: the tail's body, a little darker (light reaches it through the strands).
  std::vector<Eigen::Vector3d> tp, tn;
  tube_sides = std::max(tube_sides, 3);
  hairTube(curve, 1.0, tube_sides, tp, tn);
  for (size_t i = 0; i < tp.size(); ++i) {
    HairVertex v{};
    put(v.pos, tp[i]);
    put(v.tangent, curve.tangents[i / size_t(tube_sides)]);
    put(v.normal, tn[i]);
    put(v.color, 0.8 * albedo);
    v.half_width = 0.0f;
    v.occlusion = 0.6f;
    mesh.vertices.push_back(v);
  }
  const uint32_t sides = uint32_t(tube_sides);
  // Rings i and j of the tube, quad by quad.
  const auto tubeBand = [&](std::vector<uint32_t>& out, uint32_t i, uint32_t j) {
    for (uint32_t k = 0; k < sides; ++k) {
      const uint32_t a = i * sides + k, b = i * sides + (k + 1) % sides;
      const uint32_t c = j * sides + k, d = j * sides + (k + 1) % sides;
      out.insert(out.end(), {a, b, d, a, d, c});
    }
  };
  // The shadow pass's spans of samples 0..last along a line through pos(0..last): from each kept
  // sample, as many (up to 3) are skipped as lie within `tol` of the chord to the next kept one.
  const double tol = kShadowChordTolerance * hair.width;
  const auto shadowSpans = [tol](uint32_t last, auto&& pos, auto&& band) {
    for (uint32_t i = 0; i < last;) {
      uint32_t j = i + 1;
      for (uint32_t k = i + 2; k <= std::min(i + 4, last); ++k) {
        const Eigen::Vector3d a = pos(i), u = (pos(k) - a).normalized();
        bool straight = true;
        for (uint32_t q = i + 1; q < k && straight; ++q) {
          const Eigen::Vector3d d = pos(q) - a;
          straight = (d - d.dot(u) * u).norm() <= tol;
        }
        if (!straight) break;
        j = k;
      }
      band(i, j);
      i = j;
    }
  };
  for (uint32_t i = 0; i + 1 < uint32_t(m); ++i) tubeBand(mesh.indices, i, i + 1);
  shadowSpans(
      uint32_t(m - 1), [&](uint32_t i) { return curve.points[i]; },
      [&](uint32_t i, uint32_t j) { tubeBand(mesh.shadow_indices, i, j); });

  // The strands: roots spread evenly over the tie's disc (Vogel's sunflower), each following the
  // curve at its own offset in the curve's frame, the clump widening toward the tip.
  // Where the tail bends tighter than the clump is wide, the strands on the inside of the bend
  // would fold back into a loop: the clump is squeezed there by a smooth factor of the curvature
  // (itself smoothed along the curve, as the spline's curvature jumps at the joints).
  std::vector<double> kappa(m, 0.0), squeeze(m, 1.0);
  for (size_t i = 0; i < m; ++i) {
    const size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, m - 1);
    const double ds = (curve.s[b] - curve.s[a]) * curve.length;
    kappa[i] = ds > 0.0 ? (curve.tangents[b] - curve.tangents[a]).norm() / ds : 0.0;
  }
  // Box filter over half a link, three times (close to a Gaussian): continuous at the joints.
  const size_t half = std::max<size_t>(
      1, curve.joint_samples.size() > 1 ? size_t(curve.joint_samples[1] - curve.joint_samples[0]) / 2 : 1);
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<double> k = kappa;
    for (size_t i = 0; i < m; ++i) {
      double sum = 0.0;
      int n = 0;
      for (size_t j = i >= half ? i - half : 0; j <= std::min(i + half, m - 1); ++j, ++n) sum += k[j];
      kappa[i] = sum / double(n);
    }
  }
  for (size_t i = 0; i < m; ++i) {
    const double reach = kappa[i] * curve.radius[i] * (1.0 + hair.spread * curve.s[i] * curve.s[i]) *
                         (1.0 + hair.noise * 1.5 * curve.s[i]) / 0.5;
    squeeze[i] = 1.0 / std::sqrt(1.0 + reach * reach * reach * reach);
  }
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  const double var = std::clamp(hair.color_variation, 0.0, 1.0);
  std::vector<Eigen::Vector3d> pos(m);
  for (int k = 0; k < strands; ++k) {
    const uint32_t id = uint32_t(k);
    const double rho = 0.95 * std::sqrt((double(k) + 0.5) / double(strands));
    const double theta = double(k) * golden;
    const double end = 1.0 - 0.35 * std::pow(hash01(id, 1), 2.0);  // some strands are shorter
    const double freq = 1.5 + 2.0 * hash01(id, 2), ph1 = 2.0 * kPi * hash01(id, 3), ph2 = 2.0 * kPi * hash01(id, 4);
    const double amp = hair.noise * (0.5 + hash01(id, 5));
    const double bright = 1.0 + var * (2.0 * hash01(id, 6) - 1.0);
    const double warm = 1.0 + 0.5 * var * (2.0 * hash01(id, 7) - 1.0);  // redder or cooler
    const Eigen::Vector3d col = (albedo.array() * Eigen::Array3d(warm, 1.0, 1.0 / warm) * bright).matrix();
    const size_t last = std::min(std::max(size_t(std::lround(end * double(m - 1))), size_t(2)), m - 1);
    for (size_t i = 0; i <= last; ++i) {
      const double s = curve.s[i];
      const double R = curve.radius[i] * (1.0 + hair.spread * s * s) * squeeze[i];
      const double wob = amp * s;  // tied at the root, free at the tip
      const double x = rho * std::cos(theta) + wob * std::sin(2.0 * kPi * freq * s + ph1);
      const double y = rho * std::sin(theta) + wob * std::sin(2.0 * kPi * 1.3 * freq * s + ph2);
      pos[i] = curve.points[i] + R * (x * curve.normals[i] + y * curve.binormal(i));
    }
    const uint32_t base = uint32_t(mesh.vertices.size());
    for (size_t i = 0; i <= last; ++i) {
      const double s = curve.s[i];
      Eigen::Vector3d t = (i == 0 ? pos[1] - pos[0] : i == last ? pos[i] - pos[i - 1] : pos[i + 1] - pos[i - 1]);
      t = t.norm() > 1e-12 ? t.normalized() : curve.tangents[i];
      const Eigen::Vector3d out = perpendicular(t, pos[i] - curve.points[i] + 1e-6 * curve.normals[i]);
      const double along = double(i) / double(last);
      const float hw = float(0.5 * hair.width * (1.0 - 0.75 * along * along));
      const double depth = std::clamp(rho / 0.95, 0.0, 1.0);
      const float occl = float(std::clamp(0.45 + 0.55 * depth + 0.5 * s, 0.0, 1.0));
      for (float side : {-1.0f, 1.0f}) {
        HairVertex v{};
        put(v.pos, pos[i]);
        put(v.tangent, t);
        put(v.normal, out);
        put(v.color, col);
        v.half_width = side * hw;
        v.occlusion = occl;
        mesh.vertices.push_back(v);
      }
    }
    // Samples i and j of the strand: a quad of its ribbon.
    const auto ribbon = [&](std::vector<uint32_t>& out, uint32_t i, uint32_t j) {
      const uint32_t a = base + 2 * i, b = base + 2 * j;
      out.insert(out.end(), {a, a + 1, b + 1, a, b + 1, b});
    };
    for (uint32_t i = 0; i < uint32_t(last); ++i) ribbon(mesh.indices, i, i + 1);
    shadowSpans(
        uint32_t(last), [&](uint32_t i) { return pos[i]; },
        [&](uint32_t i, uint32_t j) { ribbon(mesh.shadow_indices, i, j); });
  }
  mesh.strands = size_t(std::max(strands, 0));
  return mesh;
}

}  // namespace ponyhop

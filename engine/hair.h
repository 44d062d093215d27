// The ponytail dressed as hair (CPU side, no GL): a smooth curve through the chain's joints with
// rotation-minimizing frames, a tapered core tube along it, and a clump of thin strands around it
// that spread toward the tip. Renderer::drawHair draws the result with an anisotropic
// (Kajiya-Kay, two-lobe) hair shader; the physics chain is not touched.
//
//   HairCurve c = hairCurve(joints, radii, reference);   // joints: anchor, link ends..., tip
//   HairMesh m = buildHair(c, scene.chain->hair, color, strands);
//   renderer.drawHair(m);
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "sim/scene.h"

namespace ponyhop {

// A curve sampled densely, root first. s: 0 at the root .. 1 at the tip (by arc length).
struct HairCurve {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> tangents;  // unit, toward the tip
  std::vector<Eigen::Vector3d> normals;   // unit, rotation-minimizing, perpendicular to the tangent
  std::vector<double> radius;             // m, the links' radius interpolated along the curve
  std::vector<double> dradius;            // d radius / d arc length (the same spline: continuous)
  double length = 0.0;                    // m, arc length
  std::vector<double> s;                  // 0..1, arc length fraction
  std::vector<int> joint_samples;         // the sample index of each input point
  Eigen::Vector3d binormal(size_t i) const { return tangents[i].cross(normals[i]); }
};

// Centripetal Catmull-Rom spline through `points` (tangent-continuous at every point, no cusps or
// self-intersections within a segment), `per_segment` samples per span. `radii[i]` is the radius
// at points[i]. Frames are carried along by the double-reflection method (Wang et al. 2008): no
// twist is added, and the first normal is `reference` made perpendicular to the first tangent (the
// parent body's axis: strands stay put on the head instead of swimming from frame to frame).
HairCurve hairCurve(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& radii,
                    const Eigen::Vector3d& reference, int per_segment = 6);

// One vertex of the hair draw. A strand vertex lies on the strand's centre line and is pushed
// sideways by `half_width` (signed) in the vertex shader, facing the camera (or the light in the
// shadow pass); a core tube vertex has half_width 0 and is drawn where it is.
struct HairVertex {
  float pos[3];
  float tangent[3];  // along the strand, toward the tip
  float normal[3];   // outward from the tail's axis (tube: the surface normal)
  float color[3];    // linear albedo
  float half_width;  // m, signed; 0: a tube vertex
  float occlusion;   // 0..1, light reaching this point through the clump (1: none blocked)
};

// The shading constants of one hair draw.
struct HairShading {
  float highlight = 0.35f;  // strength of the primary (white) lobe; the secondary (tinted) is half
  float shift = 0.12f;      // tangent shift of the primary lobe (the secondary gets -1.5x)
};

// How far (in strand widths, HairParams::width) a sample the shadow pass leaves out may lie from
// the chord that replaces it (HairMesh::shadow_indices).
inline constexpr double kShadowChordTolerance = 1.0;

struct HairMesh {
  std::vector<HairVertex> vertices;
  std::vector<uint32_t> indices;  // triangles
  // The same surfaces for the shadow pass, through fewer samples along the tail: a sample is left
  // out where it lies within kShadowChordTolerance strand widths of the chord between its kept
  // neighbours (so within a fraction of a shadow texel), its first and last kept. Fewer triangles
  // are what a software rasterizer pays for in that pass.
  std::vector<uint32_t> shadow_indices;
  HairShading shading;
  size_t strands = 0;
};

// The strand count of `hair` at the given quality (draft: strands_draft).
int hairStrandCount(const HairParams& hair, bool draft);

// The tail: a core tube (`tube_sides` around, radius 0.8 x the curve's) and `strands` strands,
// coloured `color` (display sRGB) with the per-strand variation of `hair`. Deterministic: the
// same inputs give the same mesh.
HairMesh buildHair(const HairCurve& curve, const HairParams& hair, const Eigen::Vector3f& color, int strands,
                   int tube_sides = 12);

// The core tube alone (what the strands are combed around): positions and surface normals,
// `sides` vertices per curve sample, ring by ring. Used by buildHair and by the tests.
void hairTube(const HairCurve& curve, double radius_scale, int sides, std::vector<Eigen::Vector3d>& positions,
              std::vector<Eigen::Vector3d>& normals);

}  // namespace ponyhop

// Static geometry the renderer builds once and reuses every frame (CPU side, no GL here):
// the hull template for spheres/capsules/tapered capsules (shaped in the vertex shader, see
// kCapsuleVS in shaders.cpp) and bounds helpers for the draw list.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

namespace ponyhop {

// Vertex = (cos azimuth, sin azimuth, t along the cap 0..1, cap 0 or 1). `slices` around the axis,
// `rings` per cap; the cone between the caps is the band joining the two last rings.
struct HullTemplate {
  std::vector<std::array<float, 4>> vertices;
  std::vector<uint32_t> indices;
};
HullTemplate makeHullTemplate(int slices, int rings);

// Axis-aligned bounds of the convex hull of two spheres.
Eigen::AlignedBox3d hullBounds(const Eigen::Vector3d& p0, double r0, const Eigen::Vector3d& p1, double r1);
// Bounds of a transformed box (all 8 corners).
Eigen::AlignedBox3d transformedBounds(const Eigen::Affine3d& T, const Eigen::AlignedBox3d& local);

}  // namespace ponyhop

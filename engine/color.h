// Colour helpers shared by the renderer and the hair shading.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <concepts>

namespace ponyhop {

// An sRGB-encoded component to linear light (the IEC 61966-2-1 curve), clamped to [0, 1], in the
// precision of its argument (the renderer's colours are float, the hair's albedo double).
template <std::floating_point T>
T srgbToLinear(T c) {
  c = std::clamp(c, T(0), T(1));
  return c <= T(0.04045) ? c / T(12.92) : std::pow((c + T(0.055)) / T(1.055), T(2.4));
}
inline Eigen::Vector3f srgbToLinear(const Eigen::Vector3f& c) {
  return {srgbToLinear(c.x()), srgbToLinear(c.y()), srgbToLinear(c.z())};
}

}  // namespace ponyhop

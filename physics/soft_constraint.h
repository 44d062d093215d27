// Soft constraints (Hecker lecture, "Soft Constraints": damped springs, PDCs, servos):
//
//   f_c = k_s (C - C_d) + k_d (C' - C_d')
//
// applied along the Jacobian of C, as a constraint force would be (f_c J^T), but with f_c given
// by the spring-damper law instead of solved for. The controller's force laws must be smooth (no
// if, abs, min, max): the end stops use the smooth ramp below instead of max(0, x).
#pragma once

#include <cmath>

namespace ponyhop {

// f = k_s (C - C_d) + k_d (C' - C_d'): the soft constraint's generalized force (sign: it acts
// against the error, so the caller applies -f along the Jacobian).
inline double softConstraintForce(double ks, double kd, double c, double c_desired, double c_dot,
                                  double c_dot_desired = 0.0) {
  return ks * (c - c_desired) + kd * (c_dot - c_dot_desired);
}

// A smooth ramp: ~max(0, x) for |x| >> eps, (x + sqrt(x^2 + eps^2)) / 2 (value eps/2 at 0, below
// eps^2 / (4 |x|) for x << 0). Its derivative is smoothStep.
inline double smoothRamp(double x, double eps) { return 0.5 * (x + std::sqrt(x * x + eps * eps)); }
// A smooth step from 0 to 1 over ~eps around 0: (1 + x / sqrt(x^2 + eps^2)) / 2.
inline double smoothStep(double x, double eps) { return 0.5 * (1.0 + x / std::sqrt(x * x + eps * eps)); }

}  // namespace ponyhop

// Symplectic (semi-implicit) Euler: velocities first, then positions with the new velocities.
// First order; one force evaluation per step; good long-run energy behaviour for conservative
// systems (bounded oscillation instead of drift).
#pragma once

#include "physics/integrator.h"
#include "physics/rigid_body.h"

namespace ponyhop {

// One body's step in place from its accelerations a, alpha at (t, s). Always inlined: as a call
// (GCC left it one) the state it writes and the caller reads back goes through the call's spills.
[[gnu::always_inline]] inline void symplecticEulerStep(double h, const Eigen::Vector3d& a, const Eigen::Vector3d& alpha,
                                                       BodyState& s) {
  s.v += h * a;
  s.w += h * alpha;
  s.x += h * s.v;
  // Rotate by the new angular velocity over h (exact exponential map for constant w).
  s.q = renormalized(quaternionFromRotationVector(h * s.w) * s.q);
}

// acc: accelerations at (t, state) (already computed by the force stages).
void symplecticEulerStep(double h, const Accelerations& acc, State& state);

}  // namespace ponyhop

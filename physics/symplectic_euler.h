// Symplectic (semi-implicit) Euler: velocities first, then positions with the new velocities.
// First order; one force evaluation per step; good long-run energy behaviour for conservative
// systems (bounded oscillation instead of drift).
#pragma once

#include "physics/integrator.h"

namespace ponyhop {

// acc: accelerations at (t, state) (already computed by the force stages).
void symplecticEulerStep(double h, const Accelerations& acc, State& state);

}  // namespace ponyhop

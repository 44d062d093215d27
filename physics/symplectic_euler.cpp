#include "physics/symplectic_euler.h"

#include "physics/rigid_body.h"

namespace ponyhop {

void symplecticEulerStep(double h, const Accelerations& acc, State& state) {
  for (size_t i = 0; i < state.size(); ++i) {
    BodyState& s = state[i];
    s.v += h * acc[i].a;
    s.w += h * acc[i].alpha;
    s.x += h * s.v;
    // Rotate by the new angular velocity over h (exact exponential map for constant w).
    s.q = renormalized(quaternionFromRotationVector(h * s.w) * s.q);
  }
}

}  // namespace ponyhop

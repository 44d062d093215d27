#include "physics/symplectic_euler.h"

#include "physics/rigid_body.h"

namespace ponyhop {

void symplecticEulerStep(double h, const Accelerations& acc, State& state) {
  for (size_t i = 0; i < state.size(); ++i) symplecticEulerStep(h, acc[i].a, acc[i].alpha, state[i]);
}

}  // namespace ponyhop

// Classical fourth-order Runge-Kutta on the full state y = (x, q, v, w), y' = (v, 1/2 w q, a,
// alpha): four evaluations of the accelerations per step (the constraints are re-solved at
// t, t + h/2, t + h/2, t + h with the kinematic bodies at those times). Stage quaternions are
// used as they are (the acceleration function normalizes for its rotation matrices); the final
// quaternion is renormalized.
#pragma once

#include "physics/integrator.h"

namespace ponyhop {

// The stages' states and accelerations, kept by the caller between steps (a steady step
// allocates nothing once they are sized).
struct Rk4Work {
  State y1, y2, y3, y4;
  Accelerations k2, k3, k4;
};

// k1: accelerations at (t, state), already computed; f evaluates the other three stages.
void rk4Step(double t, double h, const Accelerations& k1, const AccelerationFunction& f, State& state, Rk4Work& work);

}  // namespace ponyhop

// Linearly implicit (Rosenbrock-)Euler for stiff soft constraints: the hopper's leg spring and
// end stops, stiff servos, the ponytail's joint damping and bending stiffness. Explicit methods
// (symplectic Euler, RK4, RATTLE) are stable only for h omega < 2..2.8 with omega = sqrt(k / m)
// of the stiffest spring; a stop of 2e6 N/m on a 0.3 kg foot (omega ~ 2600 rad/s) needs
// h < 0.8 ms. Backward Euler is stable for any h (L-stable: the stiff modes are damped, not
// amplified), at first order and with numerical damping of the fast modes.
//
// Why this one (and not implicit midpoint): a stiff stop must not ring or gain energy when h
// omega >> 1; the implicit midpoint rule is A-stable but not L-stable (|R(inf)| = 1: a stiff mode
// keeps its amplitude and flips sign every step), backward Euler damps it. Linearizing once per
// step (one linear solve, no Newton loop) keeps the cost predictable; the force law is smooth
// (the controller contract), so one linearization is enough.
//
// With F(q, v) the external and controller forces (gyroscopic torque -w x I w added, explicit),
// K = dF/dq and D = dF/dv (finite differences over each dynamic body's 6 position and 6
// velocity coordinates: rotations as world rotation vectors), backward Euler
//   M dv = h F(q + h v', v') + h J^T lambda,   v' = v + dv
// linearized, F(q + h v', v') ~ F + K h (v + dv) + D dv, with the joints at velocity level
// J v' = -J_k v_k(t + h), is one sparse KKT solve (Eigen SparseLU):
//
//   [ M - h D - h^2 K   J^T ] [ dv  ]   [ h F + h^2 K v   ]
//   [ J                 0   ] [ -h lambda ] = [ -J v - J_k v_k  ]
//
// then x += h v', q = exp(h w') q. Joint drift at position level is left to the stabilization
// stage (projection, the default), as with the other non-RATTLE methods.
// Cost: 12 force evaluations per dynamic body per step for K and D (each evaluation computes
// every force element, so O(n^2) for n bodies: meant for the hopper and ponytail-sized chains).
#pragma once

#include "physics/integrator.h"

namespace ponyhop {

ConstrainedStepResult linearlyImplicitEulerStep(double t, double h, ConstrainedStep& step);

}  // namespace ponyhop

// RATTLE for rigid bodies with Lagrange-multiplier joints (Andersen 1983; Leimkuhler & Reich,
// "Simulating Hamiltonian Dynamics", ch. 7): a constrained Stormer-Verlet step that keeps both the
// positions and the velocities on the constraint manifold every step, symplectic and
// time-reversible for conservative forces, so the energy error stays bounded (no drift) over long
// runs instead of growing as with explicit methods plus projection.
//
// Momenta p = m v and world angular momentum L = I_world w (dL/dt = torque in the world frame:
// no gyroscopic term to integrate). One step of h from (t, x, q, p, L):
//
//   kick    p+ = p + h/2 (F + F_c(mu)),   L+ = L + h/2 (t + t_c(mu)),   [F_c; t_c] = J(q_n)^T mu
//   drift   x' = x + h p+ / m,  q' = Phi_h(q; L+)   (free rigid-body flow with L+ held, below)
//   solve   mu such that C(x', q') = 0                  (position multipliers: SHAKE)
//   kick    p' = p+ + h/2 (F' + F_c(nu)),  L' = L+ + h/2 (t' + t_c(nu)),  J(q') = J at (x', q')
//   solve   nu such that J(q') v' = -J_k v_k(t + h)     (velocity multipliers)
//
// Lie-group variant (the rotational drift Phi_h): the free rigid body's Hamiltonian in the body
// frame, H = |Pi|^2 / (2 I_0) + sum_{i=1,2} (1/I_i - 1/I_0) Pi_i^2 / 2 (Pi = R^T L, I_i the
// principal inertias), is split into pieces whose flows are exact rotations: the first turns the
// body about the fixed world vector L by h |L| / I_0, the others about body axis i by
// h (1/I_i - 1/I_0) Pi_i. Their Strang composition A(h/2) B(h/2) C(h) B(h/2) A(h/2) is symplectic,
// reversible and second order, keeps |L| and the orientation exactly unit (no renormalization),
// and is EXACT for a symmetric body (I_0 = I_1: B vanishes and A, C commute): the chain's
// cylinders, the hopper's body and leg. For any axially symmetric body the two commuting pieces
// are taken as two rotations. Fast turning (the whip's last links at hundreds of rad/s) therefore
// costs no stability, only the accuracy of the coupling through the joints.
//
// The position solve is a quasi-Newton (chord) iteration: C(mu + dmu) ~ C + (h^2 / 2) A dmu with
// the symmetric A = J M^-1 J^T, first at q_n (the factorization the last step's velocity solve
// left in the World's solver when nothing has changed since, RattleWork::holds; else factored
// here), refactored at the latest iterate when an iteration contracts by less than 4x; until
// max |C| <= tolerance. Only positions are iterated. It starts from the caller's
// guess: World passes the previous accepted step's mu (warm start: mu is a force, it changes by
// O(h) per step, so the guess is as close as the acceleration-level lambda of the step's start
// that was used before, and costs no solve). The velocity solve is exact (linear): the
// mass-metric velocity projection at the new positions.
//
// Velocity-dependent forces (damping, drag, servos): the second kick is the trapezoidal rule's
// implicit half, p' = p+ + h/2 F(t + h, q', v'). Taking F at the predicted velocity v+ = p+ / m
// (explicit) makes its error O(h) in F, O(h^2) per step in v': first order. With
// `correct_velocity_forces` one fixed-point iteration follows: F again at (t + h, q', v'), the
// second kick redone from the same p+ with it, projected again; then F's error is O(h^2), the
// local error O(h^3) and the method second order (tests/physics/rattle_order_test.cpp).
// Without such forces (gravity, springs) the predicted velocity is exact for them and the
// corrector is skipped by the caller: the step is then exactly the classical RATTLE.
// Stiff springs are explicit as in any Verlet method: stable for h omega < 2 (see
// implicit_euler.h otherwise).
// Kinematic bodies: the position solve uses their pose at t + h and the velocity solve their
// velocity at t + h; their acceleration is not needed.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "physics/constraint.h"
#include "physics/integrator.h"
#include "physics/stabilization.h"

namespace ponyhop {

// rattleStep's work space: the caller keeps it between steps so that a steady step allocates
// nothing (World does; without one the step allocates its own).
struct RattleWork {
  struct Start {
    Eigen::Vector3d x, p, l;  // position, momentum + h/2 F, angular momentum + h/2 torque
    Eigen::Quaterniond q;
  };
  std::vector<Start> start;
  ConstraintSystem jn;  // J(q_n): the first kick's constraint directions
  std::vector<Vector6d> fc, v1, f0, dv;
  Eigen::VectorXd rhs, dmu;
  ProjectionWork projection;
  std::vector<Eigen::Matrix3d> inertia, inverse_inertia;  // world frame, at the step's end
  // What the solver's factorization is (generation(), rows, positions) after the last step's
  // velocity solve: A at its end positions, the next step's chord matrix A(q_n) when nothing
  // has factored, moved, or changed the joints since (a rejected step, a restored state, a
  // contact).
  unsigned long held_generation = 0;  // 0: nothing held
  std::vector<const Constraint*> held_joints;
  std::vector<Eigen::Vector3d> held_x;
  std::vector<Eigen::Quaterniond> held_q;
  bool holds(const ConstraintSolver& solver, const std::vector<RigidBody>& bodies, const Constraints& joints) const;
  void remember(const ConstraintSolver& solver, const std::vector<RigidBody>& bodies, const Constraints& joints);
};

struct RattleOptions {
  double tolerance = 1e-12;  // m, max |C| the position solve reaches
  int max_iterations = 40;
  // The corrector of the second kick for velocity-dependent forces (above). Off: one force
  // evaluation at t + h with the predicted velocity, exact only when no force depends on the
  // velocity (World turns it off then: physics/force_elements.h, dependsOnVelocity()).
  bool correct_velocity_forces = true;
  RattleWork* work = nullptr;  // the caller's work space (null: the step allocates one)
};

// One RATTLE step of h from time t. `mu`: in, the guess of the position multipliers (any size:
// one that does not match the rows starts from zero); out, the converged ones (on failure, the
// last iterate: the caller discards it with the step). Moves the dynamic bodies in place and
// leaves the step's end point in their force scratch: force/torque = F(t + h) as used by the
// last second kick, constraint_force/torque = J(q')^T nu, a/alpha = the accelerations of the
// second kick (RATTLE's own accelerations at t + h; not the acceleration-level solve's lambda,
// they differ by the method's error). failed: the position solve did not reach the tolerance
// within max_iterations (the caller splits the step).
ConstrainedStepResult rattleStep(double t, double h, Eigen::VectorXd& mu, ConstrainedStep& step,
                                 const RattleOptions& options = {});

// The free rigid-body rotation over h with world angular momentum L (above): body-to-world q of
// a body with principal inertia `inertia` (body frame). Exact for symmetric bodies.
Eigen::Quaterniond freeRotation(const Eigen::Quaterniond& q, const Eigen::Vector3d& inertia, const Eigen::Vector3d& L,
                                double h);

}  // namespace ponyhop

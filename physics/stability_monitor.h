// Detecting an explicit step beyond its stability limit within a step or two, instead of waiting
// for the state to overflow (the 1e10 runaway check needs ~10-30 steps of exponential growth).
//
// Stiffness estimate (Hairer & Wanner, "Solving ODEs II", IV.2; Shampine's test as in DOPRI5):
// with the first-order state y = (x, phi, v, w) and its derivative f(y) = (v, w, a, alpha), the
// ratio of consecutive steps
//     rho = |f(y_{n+1}) - f(y_n)| / |y_{n+1} - y_n|
// approaches the magnitude of the dominant eigenvalue of df/dy along the motion (for a spring
// a = -omega^2 x it is omega). An explicit method is unstable on that mode when h rho exceeds its
// limit (symplectic Euler and Stormer-Verlet/RATTLE: 2; RK4: 2.83). Near the limit a mode can be
// marginal for a while, so the world stops only when h rho is beyond the limit AND the step
// increments |y_{n+1} - y_n| grew by more than `kGrowth` per step for two consecutive steps (an
// unstable mode with h omega = 4 grows ~14x per step: caught within two steps; a stable but fast
// motion, such as a whip, does not triple its increment every step).
#pragma once

#include <vector>

#include "physics/integrator.h"

namespace ponyhop {

struct RigidBody;

// atan2(y, x) for y, x >= 0 (the monitor's turn angles: half a turn's angle from |vec| and |w|
// of a quaternion), within a few ulp of std::atan2 and about a third of its cost.
double atan2NonNegative(double y, double x);

class StabilityMonitor {
 public:
  static constexpr double kGrowth = 3.0;

  void reset() {
    has_previous_ = false;
    strikes_ = 0;
  }
  // The state and its derivative at the start of a step of h. Returns true when the last two
  // steps were unstable (then hRho() and growth() say by how much).
  bool observe(double h, const State& y, const Accelerations& f, double limit);
  // The same for the state and accelerations of bodies[which[i]], read in place (no gathered
  // copy of them first).
  bool observe(double h, const std::vector<RigidBody>& bodies, const std::vector<int>& which, double limit);
  double hRho() const { return h_rho_; }
  double growth() const { return growth_; }

 private:
  // y(i), a(i), alpha(i): entry i of the observed state and its accelerations.
  template <class Y, class A, class Alpha>
  bool observeWith(double h, size_t n, const Y& y, const A& a, const Alpha& alpha, double limit);

  bool has_previous_ = false;
  State y_;
  Accelerations f_;
  double increment_ = 0.0;
  double h_rho_ = 0.0;
  double growth_ = 0.0;
  int strikes_ = 0;
};

}  // namespace ponyhop

// Projected Gauss-Seidel for contact impulses with Coulomb friction in a cone (an isotropic disc
// per contact): the solver of the collision stage (physics/collisions.h) and of the hopper's toe
// at touchdown (physics/models/hopper_foot.h).
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace ponyhop {

// When the sweeps stop, and where they start.
struct PgsSettings {
  // A sweep that changes no impulse by more than tolerance x the impulse scale (the largest
  // |u0 - target| / D_ii) and leaves no sticking contact slipping by more than 10 x tolerance of
  // it ends the solve.
  double tolerance = 1e-13;
  int max_sweeps = 5000;
  // Start from the p given (last step's impulses, in the same rows) instead of zero. The start is
  // first scaled along its own ray to the least of the problem's energy there (never above zero,
  // the energy of p = 0), so that a solve stopped early from it still cannot add energy.
  bool warm_start = false;
  // Solve each contact's three rows together, exactly, given the others' impulses (block
  // Gauss-Seidel): no contact, sticking (the 3 x 3 solve) or sliding (the direction on the disc's
  // rim at which the slip after the impulse is opposite the friction, found by bracketing and
  // bisection). A normal row coupled strongly to a tangent (a link whose sideways push turns it
  // into the surface) takes hundreds of single-row sweeps; this takes a few.
  bool exact_blocks = false;
};

struct PgsResult {
  int sweeps = 0;       // sweeps taken
  bool capped = false;  // stopped at max_sweeps before the tolerance was met
};

// Solves for impulses p with velocities u = u0 + D p (D the contact-space Delassus matrix,
// symmetric positive semidefinite):
//   normal rows    p_n >= 0,  u_n >= target_n,  p_n (u_n - target_n) = 0
//   tangent pairs  |p_t| <= mu p_n; u_t = 0 inside the disc, p_t opposite u_t on its rim
// `blocks` lists each contact's first row and its row count (1: normal only, 3: normal then two
// tangents); `mu` one coefficient per block.
PgsResult projectedGaussSeidel(const Eigen::MatrixXd& d, const Eigen::VectorXd& u0, const Eigen::VectorXd& target,
                               const std::vector<std::pair<int, int>>& blocks, const std::vector<double>& mu,
                               Eigen::VectorXd& p, const PgsSettings& settings = {});

}  // namespace ponyhop

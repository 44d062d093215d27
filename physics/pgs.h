// Projected Gauss-Seidel for contact impulses with Coulomb friction in a cone (an isotropic disc
// per contact): the solver of the collision stage (physics/collisions.h) and of the hopper's toe
// at touchdown (physics/models/hopper_foot.h).
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace ponyhop {

// Solves for impulses p with velocities u = u0 + D p (D the contact-space Delassus matrix,
// symmetric positive semidefinite):
//   normal rows    p_n >= 0,  u_n >= target_n,  p_n (u_n - target_n) = 0
//   tangent pairs  |p_t| <= mu p_n; u_t = 0 inside the disc, p_t opposite u_t on its rim
// `blocks` lists each contact's first row and its row count (1: normal only, 3: normal then two
// tangents); `mu` one coefficient per block. To 1e-13 of the impulse scale (at most 5000 sweeps).
// Returns the sweeps taken.
int projectedGaussSeidel(const Eigen::MatrixXd& d, const Eigen::VectorXd& u0, const Eigen::VectorXd& target,
                         const std::vector<std::pair<int, int>>& blocks, const std::vector<double>& mu,
                         Eigen::VectorXd& p);

}  // namespace ponyhop

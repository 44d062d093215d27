#include "physics/dense_solver.h"

namespace ponyhop {

// A = J M^-1 J^T = sum over dynamic bodies k of J_k M_k^-1 J_k^T, where J_k are the columns of
// body k: only the joints touching k contribute, so each body adds the products of its own
// blocks (a chain: 3x3 blocks on the diagonal and next to it). Kinematic bodies and the world
// have no columns in J (their motion is known), so they add nothing here.
bool DenseSolver::factor(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) {
  ++generation_;
  const int m = system.rows();
  const auto& blocks = system.blocks();
  touching_.assign(bodies.size(), {});
  for (size_t j = 0; j < blocks.size(); ++j) {
    const int ba = blocks[j].body_a;
    const int bb = blocks[j].body_b;
    if (ba != kWorldBody && bodies[ba].isDynamic()) touching_[ba].push_back({static_cast<int>(j), true});
    if (bb != kWorldBody && bodies[bb].isDynamic()) touching_[bb].push_back({static_cast<int>(j), false});
  }

  a_.setZero(m, m);
  Eigen::Matrix<double, 6, 6> minv = Eigen::Matrix<double, 6, 6>::Zero();
  for (size_t k = 0; k < bodies.size(); ++k) {
    if (touching_[k].empty()) continue;
    const RigidBody& body = bodies[k];
    minv.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / body.mass;
    minv.bottomRightCorner<3, 3>() = body.worldInverseInertia();
    for (const auto& [ji, side_i] : touching_[k]) {
      const auto& bi = blocks[ji];
      const JacobianBlock& jbi = side_i ? bi.ja : bi.jb;
      const Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::ColMajor, 6, 6> jm = jbi * minv;
      for (const auto& [jj, side_j] : touching_[k]) {
        const auto& bj = blocks[jj];
        const JacobianBlock& jbj = side_j ? bj.ja : bj.jb;
        a_.block(bi.row, bj.row, bi.rows, bj.rows).noalias() += jm * jbj.transpose();
      }
    }
  }
  // A row with no dynamic body is all zero: singular (a joint between two prescribed bodies).
  for (int r = 0; r < m; ++r) {
    if (!(a_(r, r) > 0.0)) return false;
  }
  ldlt_.compute(a_);
  return ldlt_.info() == Eigen::Success && ldlt_.isPositive();
}

Eigen::VectorXd DenseSolver::solve(const Eigen::VectorXd& rhs) const { return ldlt_.solve(rhs); }

}  // namespace ponyhop

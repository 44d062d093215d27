// Baraff's linear-time Lagrange multipliers (D. Baraff, "Linear-Time Dynamics using Lagrange
// Multipliers", SIGGRAPH 96 / CMU-RI-TR-95-44; John survey: "Baraff gives O(N) multiplier method").
//
// H = [ M  J^T ; J  0 ] (one node per dynamic body, block 6, H_ii = M_i; one node per joint
// with rows, block m_j, H_jj = 0; an edge body-joint where the joint's Jacobian block is non-zero)
// is factored as a block LDL^T in an order that follows the tree. Kinematic bodies and the world
// are not nodes (their accelerations are on the right-hand side), so a joint to the head or to
// the world is a leaf of the graph.
//
// Elimination order. Baraff eliminates leaves first, alternating bodies and joints, with no
// fill-in at all. That order needs every pivot block D_i invertible; but a joint to the world
// (or to the kinematic head) is a leaf joint node whose pivot is H_jj = 0, and a body held at two
// points (a chain fixed at both ends) gives a singular pivot even though the whole system is
// regular. So we use the variant that never meets a singular pivot:
//   1. every body node first: M is block diagonal, and eliminating body b couples exactly the
//      joints that touch b. What remains on the joint nodes is -A = -J M^-1 J^T, whose only
//      non-zero blocks are those of joint pairs sharing a body (the clique of b): no fill-in
//      beyond A's own structure. Cost: sum over bodies of deg(b)^2 blocks.
//   2. then the joint nodes, in tree order: the body-joint tree rooted at a joint, children
//      before parents (leaves first). Eliminating joint j updates only the joints still left
//      in the clique of j's parent body (its parent joint and its later siblings), which are
//      already coupled: again no fill-in. The pivots are Schur complements of the SPD matrix A,
//      hence SPD (Cholesky of <= 6 x 6 blocks, any rank-deficiency shows up as a failed pivot).
//   D_j = A_jj - sum_c L_jc D_c L_jc^T,   L_xj = A_xj D_j^-1   (x in the clique, not yet eliminated)
// Solve: forward y_x -= L_xj y_j (order), z_j = D_j^-1 y_j, backward z_j -= sum_x L_xj^T z_x.
// O(n) flops for a tree of bounded degree (chains, the hopper, the ponytail on the hopper).
//
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <limits>
#include <vector>

#include "physics/constraint_solver.h"

namespace ponyhop {

class TreeSolver final : public ConstraintSolver {
 public:
  bool factor(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) override;
  bool factorWith(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                  const std::vector<Eigen::Matrix3d>& world_inverse_inertia) override;
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const override;
  void solveInto(const Eigen::VectorXd& rhs, Eigen::VectorXd& out) const override;

  // What the last factor() saw (tests, docs).
  // Nodes of H: the tree's joints plus the dynamic bodies they touch.
  int nodeCount() const { return static_cast<int>(nodes_.size() + cliques_.size()); }
  int loopRows() const { return loop_rows_; }

 private:
  using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;

  // A joint of the tree (a node of the elimination).
  struct Node {
    int block = -1;            // its block in the ConstraintSystem
    int size = 0;              // rows
    int row = 0;               // first row in the tree-only vector
    int clique = -1;           // clique of its parent body (-1 for a root joint)
    int slot = -1;             // its position in that clique
    std::vector<int> near;     // clique positions of the joints it updates (eliminated after it)
    std::vector<int> cliques;  // every clique it belongs to, with its slot there (pairs)
    int l = 0;                 // its first L_xj (x in near, in that order) in l_ or l3_
  };
  // The joints that touch one dynamic body: A's blocks between them (dense, k x k blocks).
  struct Clique {
    int body = -1;
    std::vector<int> members;  // node indices
    int a = 0;                 // its first block in a_ or a3_ (k x k blocks, row-major by slot)
    // 1 / m of its body, and the m it was made from (a division per step only when m changed).
    double mass = std::numeric_limits<double>::quiet_NaN();
    double mass_inv = 0.0;
  };

  bool structureChanged(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) const;
  bool buildStructure(const std::vector<RigidBody>& bodies, const ConstraintSystem& system);
  // The numbers of the elimination with every block R x R (R = 3: every joint has 3 rows, all
  // blocks fixed 3 x 3; R = Eigen::Dynamic: any sizes up to 6). Same arithmetic either way.
  template <int R>
  bool factorTree(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                  const std::vector<Eigen::Matrix3d>& inverse_inertia);
  bool eliminate3();  // factorTree<3>'s step 2
  template <int R>
  void treeSolveInPlace(Eigen::VectorXd& y) const;
  // L block i and D_j^-1 of node j, as R x R (l3_ and d_inv3_ when R = 3).
  template <int R>
  auto lBlock(int i) const {
    if constexpr (R == 3)
      return Eigen::Map<const Eigen::Matrix3d>(l3_[i].data());
    else
      return Eigen::Map<const Eigen::Matrix<double, R, R, Eigen::ColMajor, 6, 6>>(l_[i].data(), l_[i].rows(),
                                                                                  l_[i].cols());
  }
  template <int R>
  auto dInvBlock(int j) const {
    if constexpr (R == 3)
      return Eigen::Map<const Eigen::Matrix3d>(d_inv3_[j].data());
    else
      return Eigen::Map<const Eigen::Matrix<double, R, R, Eigen::ColMajor, 6, 6>>(d_inv_[j].data(), d_inv_[j].rows(),
                                                                                  d_inv_[j].cols());
  }
  // A_tt^-1 r for a vector over the tree rows (tree_row numbering).
  void treeSolve(const Eigen::VectorXd& r_tree, Eigen::VectorXd& y_tree) const;

  // Structure (recomputed when it changes).
  std::vector<int> signature_;
  std::vector<Node> nodes_;
  std::vector<Clique> cliques_;
  std::vector<int> order_;        // node indices, children before parents
  std::vector<int> tree_blocks_;  // system blocks in the tree, in system order
  std::vector<int> loop_blocks_;  // system blocks closing loops
  std::vector<int> tree_row_of_;  // per system row: row in the tree vector or -1
  std::vector<int> loop_row_of_;  // per system row: row in the loop vector or -1
  int tree_rows_ = 0;
  int loop_rows_ = 0;
  bool all_three_ = false;         // every tree joint has 3 rows (chains of spherical joints): fixed 3 x 3 blocks
  std::vector<JacobianBlock> jm_;  // step 1 work space: J_xb M_b^-1 per clique member
  // Step 1 for a clique of point joints (J = s [I, -r~]): per member r~ I^-1, r and s.
  std::vector<Eigen::Matrix3d> arm_inertia_;
  std::vector<Eigen::Vector3d> arm_;
  std::vector<double> sign_;
  std::vector<Eigen::Matrix3d> inverse_inertia_;  // factor()'s own R I^-1 R^T per dynamic body
  // The numbers of the elimination, each kind in one contiguous array: every clique's A blocks
  // (clique by clique), D_j^-1 per node, the L_xj (node by node). Fixed 3 x 3 blocks when every
  // tree joint has 3 rows (a3_, d_inv3_, l3_), else blocks of any size up to 6 (a_, d_inv_, l_).
  std::vector<Block> a_, d_inv_, l_;
  std::vector<Eigen::Matrix3d> a3_, d_inv3_, l3_;
  std::vector<int> near_row_;  // per L_xj: the first row of x (the solve reads no clique or node of x)

  // Numbers (refreshed by every factor()).
  Eigen::MatrixXd a_tl_;  // tree rows x loop rows: J_t M^-1 J_l^T
  Eigen::MatrixXd g_;     // A_tt^-1 A_tl
  Eigen::LDLT<Eigen::MatrixXd> schur_;
  mutable Eigen::VectorXd r_tree_, r_loop_, y_tree_, y_loop_;  // solve()'s work space
};

}  // namespace ponyhop

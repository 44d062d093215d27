#include "physics/tree_solver.h"

#include <algorithm>
#include <numeric>
#include <type_traits>
#include <utility>

#include "physics/small_matrix.h"

namespace ponyhop {

namespace {

int findRoot(std::vector<int>& up, int i) {
  while (up[i] != i) i = up[i] = up[up[i]];
  return i;
}

}  // namespace

// The structure is what the elimination order depends on: which joints have rows, between
// which bodies, and which bodies are dynamic. A contact changing its mode changes it.
bool TreeSolver::structureChanged(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) const {
  const auto& blocks = system.blocks();
  const size_t n = 1 + bodies.size() + 3 * blocks.size();
  if (signature_.size() != n || signature_[0] != static_cast<int>(bodies.size())) return true;
  size_t k = 1;
  for (const RigidBody& b : bodies) {
    if (signature_[k++] != (b.isDynamic() ? 1 : 0)) return true;
  }
  for (const auto& b : blocks) {
    if (signature_[k] != b.body_a || signature_[k + 1] != b.body_b || signature_[k + 2] != b.rows) return true;
    k += 3;
  }
  return false;
}

bool TreeSolver::buildStructure(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) {
  const auto& blocks = system.blocks();
  signature_.clear();
  signature_.push_back(static_cast<int>(bodies.size()));
  for (const RigidBody& b : bodies) signature_.push_back(b.isDynamic() ? 1 : 0);
  for (const auto& b : blocks) signature_.insert(signature_.end(), {b.body_a, b.body_b, b.rows});

  nodes_.clear();
  cliques_.clear();
  order_.clear();
  tree_blocks_.clear();
  loop_blocks_.clear();
  tree_row_of_.assign(system.rows(), -1);
  loop_row_of_.assign(system.rows(), -1);
  tree_rows_ = loop_rows_ = 0;

  // Spanning forest over the dynamic bodies (union-find): a joint whose two dynamic bodies are
  // already connected closes a loop and goes to the Schur complement.
  std::vector<int> up(bodies.size());
  std::iota(up.begin(), up.end(), 0);
  std::vector<int> body_clique(bodies.size(), -1);
  std::vector<std::vector<int>> joints_of;  // per clique: tree joints touching its body
  for (size_t j = 0; j < blocks.size(); ++j) {
    const auto& b = blocks[j];
    if (b.rows == 0) continue;
    const bool da = dynamicBody(bodies, b.body_a), db = dynamicBody(bodies, b.body_b);
    if (!da && !db) return false;  // a joint between two prescribed bodies: a zero row block
    if (da && db && findRoot(up, b.body_a) == findRoot(up, b.body_b)) {
      loop_blocks_.push_back(static_cast<int>(j));
      for (int r = 0; r < b.rows; ++r) loop_row_of_[b.row + r] = loop_rows_ + r;
      loop_rows_ += b.rows;
      continue;
    }
    if (da && db) up[findRoot(up, b.body_a)] = findRoot(up, b.body_b);
    tree_blocks_.push_back(static_cast<int>(j));
    for (int r = 0; r < b.rows; ++r) tree_row_of_[b.row + r] = tree_rows_ + r;
    Node n;
    n.block = static_cast<int>(j);
    n.size = b.rows;
    n.row = tree_rows_;
    tree_rows_ += b.rows;
    for (int body : {da ? b.body_a : -1, db ? b.body_b : -1}) {
      if (body < 0) continue;
      if (body_clique[body] < 0) {
        body_clique[body] = static_cast<int>(cliques_.size());
        cliques_.push_back(Clique{body, {}, 0});
        joints_of.emplace_back();
      }
      joints_of[body_clique[body]].push_back(static_cast<int>(nodes_.size()));
    }
    nodes_.push_back(n);
  }

  // Breadth-first over the body-joint tree, rooted at a joint: a clique's first member is its
  // parent joint, the others its child joints in BFS order. Eliminating joints in reverse BFS
  // order (children first), joint j at slot s of its parent clique is followed by exactly the
  // members at slots 0..s-1 (its parent joint and its earlier siblings): those it updates.
  std::vector<char> joint_seen(nodes_.size(), 0), clique_seen(cliques_.size(), 0);
  std::vector<int> bfs;
  const auto cliquesOf = [&](int node) {
    std::vector<int> out;
    const auto& b = blocks[nodes_[node].block];
    for (int body : {b.body_a, b.body_b}) {
      if (dynamicBody(bodies, body)) out.push_back(body_clique[body]);
    }
    return out;
  };
  for (size_t root = 0; root < nodes_.size(); ++root) {
    if (joint_seen[root]) continue;
    joint_seen[root] = 1;
    size_t head = bfs.size();
    bfs.push_back(static_cast<int>(root));
    while (head < bfs.size()) {
      const int j = bfs[head++];
      for (int c : cliquesOf(j)) {
        if (clique_seen[c]) continue;
        clique_seen[c] = 1;
        Clique& cl = cliques_[c];
        cl.members.push_back(j);
        nodes_[j].cliques.insert(nodes_[j].cliques.end(), {c, 0});
        for (int x : joints_of[c]) {
          if (joint_seen[x]) continue;
          joint_seen[x] = 1;
          nodes_[x].clique = c;
          nodes_[x].slot = static_cast<int>(cl.members.size());
          nodes_[x].cliques.insert(nodes_[x].cliques.end(), {c, nodes_[x].slot});
          for (int y = 0; y < nodes_[x].slot; ++y) nodes_[x].near.push_back(y);
          cl.members.push_back(x);
          bfs.push_back(x);
        }
      }
    }
  }
  // Every block at its size once (the factorization then writes them in place), and the
  // fixed 3 x 3 path when every tree joint has 3 rows.
  all_three_ = true;
  for (const Node& n : nodes_) all_three_ = all_three_ && n.size == 3;
  size_t widest = 0, a_blocks = 0, l_blocks = 0;
  for (Clique& cl : cliques_) {
    const size_t k = cl.members.size();
    widest = std::max(widest, k);
    cl.a = static_cast<int>(a_blocks);
    a_blocks += k * k;
  }
  near_row_.clear();
  for (Node& n : nodes_) {
    n.l = static_cast<int>(l_blocks);
    l_blocks += n.near.size();
    for (int x : n.near) near_row_.push_back(nodes_[cliques_[n.clique].members[x]].row);
  }
  a_.clear();
  d_inv_.clear();
  l_.clear();
  a3_.clear();
  d_inv3_.clear();
  l3_.clear();
  if (all_three_) {
    a3_.assign(a_blocks, Eigen::Matrix3d::Zero());
    d_inv3_.assign(nodes_.size(), Eigen::Matrix3d::Zero());
    l3_.assign(l_blocks, Eigen::Matrix3d::Zero());
  } else {
    a_.resize(a_blocks);
    d_inv_.resize(nodes_.size());
    l_.resize(l_blocks);
    for (Clique& cl : cliques_) {
      const size_t k = cl.members.size();
      for (size_t x = 0; x < k; ++x) {
        for (size_t y = 0; y < k; ++y)
          a_[cl.a + x * k + y].resize(nodes_[cl.members[x]].size, nodes_[cl.members[y]].size);
      }
    }
    for (Node& n : nodes_) {
      d_inv_[&n - nodes_.data()].resize(n.size, n.size);
      if (n.clique < 0) continue;
      for (size_t i = 0; i < n.near.size(); ++i)
        l_[n.l + i].resize(nodes_[cliques_[n.clique].members[n.near[i]]].size, n.size);
    }
  }
  jm_.resize(widest);
  arm_inertia_.resize(widest);
  arm_.resize(widest);
  sign_.resize(widest);
  order_.assign(bfs.rbegin(), bfs.rend());
  return true;
}

namespace {

// Block types of the elimination with R rows per joint (Eigen::Dynamic: any size up to 6).
template <int R>
struct Sizes {
  static constexpr int kMax = R == Eigen::Dynamic ? 6 : R;
  using M = Eigen::Matrix<double, R, R, Eigen::ColMajor, kMax, kMax>;
  using J = Eigen::Matrix<double, R, 6, Eigen::ColMajor, kMax, 6>;
};

// A stored block seen as R x R (fixed-size arithmetic when R = 3; the storage is the same).
template <int R, class B>
auto view(B& b) {
  using M = typename Sizes<R>::M;
  using Target = std::conditional_t<std::is_const_v<B>, const M, M>;
  return Eigen::Map<Target>(b.data(), b.rows(), b.cols());
}
template <int R, class B>
auto viewJ(B& b) {
  using J = typename Sizes<R>::J;
  using Target = std::conditional_t<std::is_const_v<B>, const J, J>;
  return Eigen::Map<Target>(b.data(), b.rows(), 6);
}
template <int R>
auto segment(Eigen::VectorXd& y, int row, int size) {
  if constexpr (R == Eigen::Dynamic) {
    return y.segment(row, size);
  } else {
    (void)size;
    return y.template segment<R>(row);
  }
}

}  // namespace

// Step 1, the bodies: each clique's blocks A_xy = J_xb M_b^-1 J_yb^T (M_b^-1 = diag(1/m, I^-1):
// J M^-1 is the linear columns over m and the angular ones times I_world^-1). Step 2, the joints,
// children first: D_j = A_jj (what is left of it), L_xj = A_xj D_j^-1, A_xy -= L_xj A_jy for the
// joints x, y still to come in j's parent clique. Every block is written in place: no allocation.
template <int R>
bool TreeSolver::factorTree(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                            const std::vector<Eigen::Matrix3d>& inverse_inertia) {
  using M = typename Sizes<R>::M;
  const auto& blocks = system.blocks();
  const auto jacobianOf = [&](int block, int body) -> const JacobianBlock& {
    return blocks[block].body_a == body ? blocks[block].ja : blocks[block].jb;
  };
  // Block (x, y) of a clique's A: a 3 x 3 matrix of a3_, or a view of a_.
  const auto blockA = [&](const Clique& cl, size_t x, size_t y) -> decltype(auto) {
    const size_t i = cl.a + x * cl.members.size() + y;
    if constexpr (R == 3) {
      return (a3_[i]);
    } else {
      return view<R>(a_[i]);
    }
  };
  for (Clique& cl : cliques_) {
    const RigidBody& body = bodies[cl.body];
    const Eigen::Matrix3d& inertia_inv = inverse_inertia[cl.body];
    if (!(body.mass == cl.mass)) {
      cl.mass = body.mass;
      cl.mass_inv = 1.0 / body.mass;
    }
    const double mass_inv = cl.mass_inv;
    const size_t k = cl.members.size();
    bool points = true;
    for (size_t x = 0; x < k && points; ++x) points = blocks[nodes_[cl.members[x]].block].point;
    if (points) {
      // Point joints: J_x = s_x [I, -r_x~] (s = +1 on body a, -1 on body b), so
      //   A_xy = s_x s_y (I / m - r_x~ I^-1 r_y~) = s_x s_y (I / m - W_x r_y~),  W_x = r_x~ I^-1,
      // whose row i is r_y x (row i of W_x) plus 1/m on the diagonal: cross products only.
      // From scalars into their destinations: a local Vector3d copy of the arm and a W built
      // column by column were stored in halves and read back whole (failed store forwarding,
      // ~40 % of this loop's samples in `perf annotate`).
      for (size_t x = 0; x < k; ++x) {
        const ConstraintSystem::Block& b = blocks[nodes_[cl.members[x]].block];
        const bool on_a = b.body_a == cl.body;
        const Eigen::Vector3d& arm = on_a ? b.arm_a : b.arm_b;
        const double r0 = arm(0), r1 = arm(1), r2 = arm(2);
        Eigen::Matrix3d& w = arm_inertia_[x];
        for (int c = 0; c < 3; ++c) {
          const double i0 = inertia_inv(0, c), i1 = inertia_inv(1, c), i2 = inertia_inv(2, c);
          w(0, c) = r1 * i2 - r2 * i1;
          w(1, c) = r2 * i0 - r0 * i2;
          w(2, c) = r0 * i1 - r1 * i0;
        }
        arm_[x](0) = r0;
        arm_[x](1) = r1;
        arm_[x](2) = r2;
        sign_[x] = on_a ? 1.0 : -1.0;
      }
      // Written entry by entry from scalars (a 3 x 3 temporary mirrored in place stalls on
      // store forwarding).
      for (size_t x = 0; x < k; ++x) {
        const Eigen::Matrix3d& w = arm_inertia_[x];
        for (size_t y = x; y < k; ++y) {
          const double r0 = arm_[y](0), r1 = arm_[y](1), r2 = arm_[y](2);
          const double s = sign_[x] * sign_[y];
          auto&& a = blockA(cl, x, y);
          if (y == x) {  // symmetric: the upper triangle only (the same expressions), mirrored
            const double e00 = s * (r1 * w(0, 2) - r2 * w(0, 1)) + s * mass_inv;
            const double e01 = s * (r2 * w(0, 0) - r0 * w(0, 2));
            const double e02 = s * (r0 * w(0, 1) - r1 * w(0, 0));
            const double e11 = s * (r2 * w(1, 0) - r0 * w(1, 2)) + s * mass_inv;
            const double e12 = s * (r0 * w(1, 1) - r1 * w(1, 0));
            const double e22 = s * (r0 * w(2, 1) - r1 * w(2, 0)) + s * mass_inv;
            a(0, 0) = e00;
            a(0, 1) = a(1, 0) = e01;
            a(0, 2) = a(2, 0) = e02;
            a(1, 1) = e11;
            a(1, 2) = a(2, 1) = e12;
            a(2, 2) = e22;
          } else {
            double e[3][3];
            for (int i = 0; i < 3; ++i) {
              e[i][0] = s * (r1 * w(i, 2) - r2 * w(i, 1));
              e[i][1] = s * (r2 * w(i, 0) - r0 * w(i, 2));
              e[i][2] = s * (r0 * w(i, 1) - r1 * w(i, 0));
              e[i][i] += s * mass_inv;
            }
            auto&& at = blockA(cl, y, x);
            for (int i = 0; i < 3; ++i) {
              for (int j = 0; j < 3; ++j) a(i, j) = at(j, i) = e[i][j];
            }
          }
        }
      }
      continue;
    }
    for (size_t x = 0; x < k; ++x) {
      const JacobianBlock& j = jacobianOf(nodes_[cl.members[x]].block, cl.body);
      jm_[x].resize(j.rows(), 6);
      auto jm = viewJ<R>(jm_[x]);
      const auto jx = viewJ<R>(j);
      jm.template leftCols<3>() = mass_inv * jx.template leftCols<3>();
      jm.template rightCols<3>().noalias() = jx.template rightCols<3>() * inertia_inv;
    }
    for (size_t x = 0; x < k; ++x) {
      const auto jm = viewJ<R>(std::as_const(jm_[x]));
      for (size_t y = x; y < k; ++y) {
        auto&& a = blockA(cl, x, y);
        a.noalias() = jm * viewJ<R>(jacobianOf(nodes_[cl.members[y]].block, cl.body)).transpose();
        if (y != x) blockA(cl, y, x) = a.transpose();
      }
    }
  }
  if constexpr (R == 3) {
    return eliminate3();
  } else {
    M d;
    for (int j : order_) {
      Node& n = nodes_[j];
      d.setZero(n.size, n.size);
      for (size_t i = 0; i < n.cliques.size(); i += 2) {
        const Clique& cl = cliques_[n.cliques[i]];
        const size_t s = n.cliques[i + 1];
        d += blockA(cl, s, s);
      }
      auto d_inv = view<R>(d_inv_[j]);
      Eigen::LLT<M> llt(d);
      if (llt.info() != Eigen::Success) return false;  // redundant rows: A is singular
      d_inv = llt.solve(M::Identity(n.size, n.size));
      if (!d_inv.allFinite()) return false;
      if (n.clique < 0) continue;
      const Clique& cl = cliques_[n.clique];
      const size_t s = n.slot;
      for (size_t i = 0; i < n.near.size(); ++i) view<R>(l_[n.l + i]).noalias() = blockA(cl, n.near[i], s) * d_inv;
      for (size_t i = 0; i < n.near.size(); ++i) {
        const auto l = view<R>(std::as_const(l_[n.l + i]));
        for (size_t m = 0; m < n.near.size(); ++m)
          blockA(cl, n.near[i], n.near[m]).noalias() -= l * blockA(cl, s, n.near[m]);
      }
    }
  }
  return true;
}

// Step 2 on fixed 3 x 3 blocks, with the symmetry of A and D_j: D_j^-1 by its cofactors,
// L_xj = A_xj D_j^-1, and A_xy -= L_xj A_jy for y >= x only (A_yx is its transpose; A_xx by its
// upper triangle, since L_xj A_jx = A_xj D_j^-1 A_xj^T is symmetric).
bool TreeSolver::eliminate3() {
  for (int j : order_) {
    const Node& n = nodes_[j];
    // D_j = sum of j's diagonal blocks, only the upper triangle that inverseSpd3 reads, in
    // scalars: the blocks were just written entry by entry (step 1, or the elimination of j's
    // child), and a Matrix3d copy of them read those stores back 16 bytes at a time (failed
    // store forwarding on the elimination's critical path).
    const Eigen::Matrix3d& d0 =
        a3_[cliques_[n.cliques[0]].a + n.cliques[1] * (cliques_[n.cliques[0]].members.size() + 1)];
    double m00 = d0(0, 0), m01 = d0(0, 1), m02 = d0(0, 2), m11 = d0(1, 1), m12 = d0(1, 2), m22 = d0(2, 2);
    for (size_t i = 2; i < n.cliques.size(); i += 2) {
      const Clique& cl = cliques_[n.cliques[i]];
      const Eigen::Matrix3d& di = a3_[cl.a + n.cliques[i + 1] * (cl.members.size() + 1)];
      m00 += di(0, 0);
      m01 += di(0, 1);
      m02 += di(0, 2);
      m11 += di(1, 1);
      m12 += di(1, 2);
      m22 += di(2, 2);
    }
    Eigen::Matrix3d& d_inv = d_inv3_[j];
    if (!inverseSpd3(m00, m01, m02, m11, m12, m22, d_inv)) return false;  // redundant rows: A is singular
    if (n.clique < 0) continue;
    const Clique& cl = cliques_[n.clique];
    const size_t k = cl.members.size(), s = n.slot;
    Eigen::Matrix3d* a = a3_.data() + cl.a;
    Eigen::Matrix3d* l = l3_.data() + n.l;
    const size_t near = n.near.size();
    for (size_t i = 0; i < near; ++i) l[i].noalias() = a[n.near[i] * k + s] * d_inv;
    for (size_t i = 0; i < near; ++i) {
      const size_t x = n.near[i];
      // A_xx -= L_xj A_xj^T (upper triangle, mirrored).
      Eigen::Matrix3d& axx = a[x * k + x];
      const Eigen::Matrix3d& axj = a[x * k + s];
      for (int r = 0; r < 3; ++r) {
        for (int c = r; c < 3; ++c) axx(r, c) = axx(c, r) = axx(r, c) - l[i].row(r).dot(axj.row(c));
      }
      for (size_t m = i + 1; m < near; ++m) {
        const size_t y = n.near[m];
        Eigen::Matrix3d& axy = a[x * k + y];
        axy.noalias() -= l[i] * a[s * k + y];
        a[y * k + x] = axy.transpose();
      }
    }
  }
  return true;
}

bool TreeSolver::factor(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) {
  inverse_inertia_.resize(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].isDynamic())
      inverse_inertia_[i] = rotateDiagonal(bodies[i].rotation(), bodies[i].inertia.cwiseInverse());
  }
  return factorWith(bodies, system, inverse_inertia_);
}

bool TreeSolver::factorWith(const std::vector<RigidBody>& bodies, const ConstraintSystem& system,
                            const std::vector<Eigen::Matrix3d>& inverse_inertia) {
  ++generation_;
  if (structureChanged(bodies, system) && !buildStructure(bodies, system)) {
    signature_.clear();
    return false;
  }
  if (!(all_three_ ? factorTree<3>(bodies, system, inverse_inertia)
                   : factorTree<Eigen::Dynamic>(bodies, system, inverse_inertia)))
    return false;
  const auto& blocks = system.blocks();
  const auto jacobianOf = [&](int block, int body) -> const JacobianBlock& {
    return blocks[block].body_a == body ? blocks[block].ja : blocks[block].jb;
  };
  const auto inverseMass = [&](int body) {
    Eigen::Matrix<double, 6, 6> minv = Eigen::Matrix<double, 6, 6>::Zero();
    minv.topLeftCorner<3, 3>().diagonal().setConstant(1.0 / bodies[body].mass);
    minv.bottomRightCorner<3, 3>() = inverse_inertia[body];
    return minv;
  };

  if (loop_rows_ == 0) return true;

  // Loop rows: A_tl = J_t M^-1 J_l^T and A_ll = J_l M^-1 J_l^T from the bodies they share,
  // then S = A_ll - A_lt A_tt^-1 A_tl with k tree solves.
  std::vector<std::vector<int>> tree_touching(bodies.size()), loop_touching(bodies.size());
  for (int t : tree_blocks_) {
    for (int b : {blocks[t].body_a, blocks[t].body_b}) {
      if (dynamicBody(bodies, b)) tree_touching[b].push_back(t);
    }
  }
  for (int l : loop_blocks_) {
    for (int b : {blocks[l].body_a, blocks[l].body_b}) loop_touching[b].push_back(l);
  }
  a_tl_.setZero(tree_rows_, loop_rows_);
  Eigen::MatrixXd a_ll = Eigen::MatrixXd::Zero(loop_rows_, loop_rows_);
  for (int l : loop_blocks_) {
    const int lrow = loop_row_of_[blocks[l].row];
    for (int b : {blocks[l].body_a, blocks[l].body_b}) {
      const Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, 6> p =
          inverseMass(b) * jacobianOf(l, b).transpose();
      for (int t : tree_touching[b]) {
        a_tl_.block(tree_row_of_[blocks[t].row], lrow, blocks[t].rows, blocks[l].rows) += jacobianOf(t, b) * p;
      }
      for (int l2 : loop_touching[b]) {
        a_ll.block(loop_row_of_[blocks[l2].row], lrow, blocks[l2].rows, blocks[l].rows) += jacobianOf(l2, b) * p;
      }
    }
  }
  g_.resize(tree_rows_, loop_rows_);
  Eigen::VectorXd col(tree_rows_);
  for (int c = 0; c < loop_rows_; ++c) {
    treeSolve(a_tl_.col(c), col);
    g_.col(c) = col;
  }
  schur_.compute(a_ll - a_tl_.transpose() * g_);
  return schur_.info() == Eigen::Success && schur_.isPositive() && schur_.vectorD().minCoeff() > 0.0;
}

// A_tt y = r over the tree, in place (y holds r on entry): forward y_x -= L_xj y_j (children
// first), z_j = D_j^-1 y_j, backward z_j -= sum_x L_xj^T z_x (parents first).
template <int R>
void TreeSolver::treeSolveInPlace(Eigen::VectorXd& y) const {
  using V = Eigen::Matrix<double, R, 1, Eigen::ColMajor, Sizes<R>::kMax, 1>;
  // x's rows from near_row_ and its size from its L block (fixed 3 when R = 3).
  const auto rowsOf = [&](int l) {
    if constexpr (R == 3)
      return 3;
    else
      return static_cast<int>(l_[l].rows());
  };
  for (int j : order_) {
    const Node& n = nodes_[j];
    auto yj = segment<R>(y, n.row, n.size);
    const int end = n.l + static_cast<int>(n.near.size());
    for (int l = n.l; l < end; ++l) segment<R>(y, near_row_[l], rowsOf(l)).noalias() -= lBlock<R>(l) * yj;
    const V z = dInvBlock<R>(j) * yj;
    yj = z;
  }
  if constexpr (R == 3) {
    // In scalars, the same operations as below (L^T y_x summed ((x0 + x1) + x2) per entry): y_x
    // was written entry by entry by the node just before, and the product read it back 16 bytes
    // at a time (failed store forwarding, a third of this function's samples at N = 8).
    double* yv = y.data();
    for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
      const Node& n = nodes_[*it];
      double* yj = yv + n.row;
      double y0 = yj[0], y1 = yj[1], y2 = yj[2];
      const int end = n.l + static_cast<int>(n.near.size());
      for (int l = n.l; l < end; ++l) {
        const double* yx = yv + near_row_[l];
        const double x0 = yx[0], x1 = yx[1], x2 = yx[2];
        const Eigen::Matrix3d& lx = l3_[l];
        y0 -= (lx(0, 0) * x0 + lx(1, 0) * x1) + lx(2, 0) * x2;
        y1 -= (lx(0, 1) * x0 + lx(1, 1) * x1) + lx(2, 1) * x2;
        y2 -= (lx(0, 2) * x0 + lx(1, 2) * x1) + lx(2, 2) * x2;
      }
      yj[0] = y0;
      yj[1] = y1;
      yj[2] = y2;
    }
    return;
  }
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    const Node& n = nodes_[*it];
    auto yj = segment<R>(y, n.row, n.size);
    const int end = n.l + static_cast<int>(n.near.size());
    for (int l = n.l; l < end; ++l) yj.noalias() -= lBlock<R>(l).transpose() * segment<R>(y, near_row_[l], rowsOf(l));
  }
}

void TreeSolver::treeSolve(const Eigen::VectorXd& r_tree, Eigen::VectorXd& y_tree) const {
  y_tree = r_tree;
  if (all_three_)
    treeSolveInPlace<3>(y_tree);
  else
    treeSolveInPlace<Eigen::Dynamic>(y_tree);
}

Eigen::VectorXd TreeSolver::solve(const Eigen::VectorXd& rhs) const {
  Eigen::VectorXd y;
  solveInto(rhs, y);
  return y;
}

void TreeSolver::solveInto(const Eigen::VectorXd& rhs, Eigen::VectorXd& y) const {
  if (loop_rows_ == 0 && tree_rows_ == rhs.size()) {
    // No loop rows: the tree's rows are the system's, in its order (buildStructure numbers them
    // block by block), so the solve runs in y itself, without the copies into and out of the
    // tree's vector (3 % of a tree step's instructions at N = 128).
    y = rhs;
    if (all_three_)
      treeSolveInPlace<3>(y);
    else
      treeSolveInPlace<Eigen::Dynamic>(y);
    return;
  }
  r_tree_.resize(tree_rows_);
  r_loop_.resize(loop_rows_);
  for (int r = 0; r < rhs.size(); ++r) {
    if (tree_row_of_[r] >= 0) r_tree_(tree_row_of_[r]) = rhs(r);
    if (loop_row_of_[r] >= 0) r_loop_(loop_row_of_[r]) = rhs(r);
  }
  treeSolve(r_tree_, y_tree_);
  if (loop_rows_ > 0) {
    // y_l = S^-1 (b_l - A_lt A_tt^-1 b_t),  y_t = A_tt^-1 b_t - G y_l.
    y_loop_ = schur_.solve(r_loop_ - a_tl_.transpose() * y_tree_);
    y_tree_ -= g_ * y_loop_;
  }
  y.setZero(rhs.size());
  for (int r = 0; r < rhs.size(); ++r) {
    if (tree_row_of_[r] >= 0) y(r) = y_tree_(tree_row_of_[r]);
    if (loop_row_of_[r] >= 0) y(r) = y_loop_(loop_row_of_[r]);
  }
}

}  // namespace ponyhop

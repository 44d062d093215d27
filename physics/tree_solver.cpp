#include "physics/tree_solver.h"

#include <algorithm>
#include <numeric>
#include <type_traits>
#include <utility>

#include "physics/small_matrix.h"

namespace ponyhop {

namespace {

bool dynamicBody(const std::vector<RigidBody>& bodies, int i) { return i != kWorldBody && bodies[i].isDynamic(); }

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
        cliques_.push_back(Clique{body, {}, {}});
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
  size_t widest = 0;
  for (Clique& cl : cliques_) {
    const size_t k = cl.members.size();
    widest = std::max(widest, k);
    cl.a.assign(k * k, Block());
    for (size_t x = 0; x < k; ++x) {
      for (size_t y = 0; y < k; ++y) cl.a[x * k + y].resize(nodes_[cl.members[x]].size, nodes_[cl.members[y]].size);
    }
  }
  all_three_ = true;
  for (Node& n : nodes_) {
    all_three_ = all_three_ && n.size == 3;
    n.d_inv.resize(n.size, n.size);
    n.l.resize(n.near.size());
    if (n.clique < 0) continue;
    for (size_t i = 0; i < n.near.size(); ++i)
      n.l[i].resize(nodes_[cliques_[n.clique].members[n.near[i]]].size, n.size);
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
  for (Clique& cl : cliques_) {
    const RigidBody& body = bodies[cl.body];
    const Eigen::Matrix3d& inertia_inv = inverse_inertia[cl.body];
    const double mass_inv = 1.0 / body.mass;
    const size_t k = cl.members.size();
    bool points = true;
    for (size_t x = 0; x < k && points; ++x) points = blocks[nodes_[cl.members[x]].block].point;
    if (points) {
      // Point joints: J_x = s_x [I, -r_x~] (s = +1 on body a, -1 on body b), so
      //   A_xy = s_x s_y (I / m - r_x~ I^-1 r_y~) = s_x s_y (I / m - W_x r_y~),  W_x = r_x~ I^-1,
      // whose row i is r_y x (row i of W_x) plus 1/m on the diagonal: cross products only.
      for (size_t x = 0; x < k; ++x) {
        const ConstraintSystem::Block& b = blocks[nodes_[cl.members[x]].block];
        const bool on_a = b.body_a == cl.body;
        const Eigen::Vector3d arm = on_a ? b.arm_a : b.arm_b;
        Eigen::Matrix3d w;
        for (int c = 0; c < 3; ++c) w.col(c) = arm.cross(inertia_inv.col(c));
        arm_[x] = arm;
        arm_inertia_[x] = w;
        sign_[x] = on_a ? 1.0 : -1.0;
      }
      // Written entry by entry from scalars (a 3 x 3 temporary mirrored in place stalls on
      // store forwarding).
      for (size_t x = 0; x < k; ++x) {
        const Eigen::Matrix3d& w = arm_inertia_[x];
        for (size_t y = x; y < k; ++y) {
          const double r0 = arm_[y](0), r1 = arm_[y](1), r2 = arm_[y](2);
          const double s = sign_[x] * sign_[y];
          double e[3][3];
          for (int i = 0; i < 3; ++i) {
            e[i][0] = s * (r1 * w(i, 2) - r2 * w(i, 1));
            e[i][1] = s * (r2 * w(i, 0) - r0 * w(i, 2));
            e[i][2] = s * (r0 * w(i, 1) - r1 * w(i, 0));
            e[i][i] += s * mass_inv;
          }
          auto a = view<R>(cl.a[x * k + y]);
          if (y == x) {  // symmetric: the upper triangle, mirrored
            for (int i = 0; i < 3; ++i) {
              for (int j = i; j < 3; ++j) a(i, j) = a(j, i) = e[i][j];
            }
          } else {
            auto at = view<R>(cl.a[y * k + x]);
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
        auto a = view<R>(cl.a[x * k + y]);
        a.noalias() = jm * viewJ<R>(jacobianOf(nodes_[cl.members[y]].block, cl.body)).transpose();
        if (y != x) view<R>(cl.a[y * k + x]) = a.transpose();
      }
    }
  }
  M d;
  for (int j : order_) {
    Node& n = nodes_[j];
    d.setZero(n.size, n.size);
    for (size_t i = 0; i < n.cliques.size(); i += 2) {
      const Clique& cl = cliques_[n.cliques[i]];
      const size_t s = n.cliques[i + 1];
      d += view<R>(std::as_const(cl.a[s * cl.members.size() + s]));
    }
    auto d_inv = view<R>(n.d_inv);
    if constexpr (R == 3) {
      Eigen::Matrix3d inv;
      if (!inverseSpd3(d, inv)) return false;  // redundant rows: A is singular
      d_inv = inv;
    } else {
      Eigen::LLT<M> llt(d);
      if (llt.info() != Eigen::Success) return false;  // redundant rows: A is singular
      d_inv = llt.solve(M::Identity(n.size, n.size));
      if (!d_inv.allFinite()) return false;
    }
    if (n.clique < 0) continue;
    Clique& cl = cliques_[n.clique];
    const size_t k = cl.members.size(), s = n.slot;
    for (size_t i = 0; i < n.near.size(); ++i) {
      view<R>(n.l[i]).noalias() = view<R>(std::as_const(cl.a[n.near[i] * k + s])) * d_inv;
    }
    for (size_t i = 0; i < n.near.size(); ++i) {
      const auto l = view<R>(std::as_const(n.l[i]));
      for (size_t m = 0; m < n.near.size(); ++m) {
        view<R>(cl.a[n.near[i] * k + n.near[m]]).noalias() -= l * view<R>(std::as_const(cl.a[s * k + n.near[m]]));
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
  for (int j : order_) {
    const Node& n = nodes_[j];
    auto yj = segment<R>(y, n.row, n.size);
    if (n.clique >= 0) {
      const Clique& cl = cliques_[n.clique];
      for (size_t i = 0; i < n.near.size(); ++i) {
        const Node& x = nodes_[cl.members[n.near[i]]];
        segment<R>(y, x.row, x.size).noalias() -= view<R>(n.l[i]) * yj;
      }
    }
    const V z = view<R>(n.d_inv) * yj;
    yj = z;
  }
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    const Node& n = nodes_[*it];
    if (n.clique < 0) continue;
    auto yj = segment<R>(y, n.row, n.size);
    const Clique& cl = cliques_[n.clique];
    for (size_t i = 0; i < n.near.size(); ++i) {
      const Node& x = nodes_[cl.members[n.near[i]]];
      yj.noalias() -= view<R>(n.l[i]).transpose() * segment<R>(y, x.row, x.size);
    }
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

#include "physics/tree_solver.h"

#include <numeric>

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
  for (Clique& cl : cliques_) cl.a.assign(cl.members.size() * cl.members.size(), Block());
  order_.assign(bfs.rbegin(), bfs.rend());
  work_.assign(nodes_.size(), Vec());
  return true;
}

bool TreeSolver::factor(const std::vector<RigidBody>& bodies, const ConstraintSystem& system) {
  if (structureChanged(bodies, system) && !buildStructure(bodies, system)) {
    signature_.clear();
    return false;
  }
  const auto& blocks = system.blocks();

  // Numbers of H: the off-diagonal block to the parent (a Jacobian block or its transpose).
  const auto jacobianOf = [&](int block, int body) -> const JacobianBlock& {
    return blocks[block].body_a == body ? blocks[block].ja : blocks[block].jb;
  };
  const auto inverseMass = [&](int body) {
    Eigen::Matrix<double, 6, 6> minv = Eigen::Matrix<double, 6, 6>::Zero();
    minv.topLeftCorner<3, 3>().diagonal().setConstant(1.0 / bodies[body].mass);
    minv.bottomRightCorner<3, 3>() = bodies[body].worldInverseInertia();
    return minv;
  };

  // Step 1, the bodies: each clique's blocks A_xy = J_xb M_b^-1 J_yb^T.
  for (Clique& cl : cliques_) {
    const Eigen::Matrix<double, 6, 6> minv = inverseMass(cl.body);
    const size_t k = cl.members.size();
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::ColMajor, 6, 6>> jm(k);
    for (size_t x = 0; x < k; ++x) jm[x] = jacobianOf(nodes_[cl.members[x]].block, cl.body) * minv;
    for (size_t x = 0; x < k; ++x) {
      for (size_t y = 0; y < k; ++y) {
        cl.a[x * k + y].noalias() = jm[x] * jacobianOf(nodes_[cl.members[y]].block, cl.body).transpose();
      }
    }
  }
  // Step 2, the joints, children first: D_j = A_jj (what is left of it), L_xj = A_xj D_j^-1,
  // A_xy -= L_xj A_jy for the joints x, y still to come in j's parent clique.
  Block d;
  for (int j : order_) {
    Node& n = nodes_[j];
    d.setZero(n.size, n.size);
    for (size_t i = 0; i < n.cliques.size(); i += 2) {
      const Clique& cl = cliques_[n.cliques[i]];
      const size_t s = n.cliques[i + 1];
      d += cl.a[s * cl.members.size() + s];
    }
    Eigen::LLT<Block> llt(d);
    if (llt.info() != Eigen::Success) return false;  // redundant rows: A is singular
    n.d_inv = llt.solve(Block::Identity(n.size, n.size));
    if (!n.d_inv.allFinite()) return false;
    n.l.resize(n.near.size());
    if (n.clique < 0) continue;
    Clique& cl = cliques_[n.clique];
    const size_t k = cl.members.size(), s = n.slot;
    for (size_t i = 0; i < n.near.size(); ++i) n.l[i] = cl.a[n.near[i] * k + s] * n.d_inv;
    for (size_t i = 0; i < n.near.size(); ++i) {
      for (size_t m = 0; m < n.near.size(); ++m) {
        cl.a[n.near[i] * k + n.near[m]].noalias() -= n.l[i] * cl.a[s * k + n.near[m]];
      }
    }
  }

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

// A_tt y = r over the tree: forward y_x -= L_xj y_j (children first), z_j = D_j^-1 y_j,
// backward z_j -= sum_x L_xj^T z_x (parents first).
void TreeSolver::treeSolve(const Eigen::VectorXd& r_tree, Eigen::VectorXd& y_tree) const {
  for (size_t j = 0; j < nodes_.size(); ++j) work_[j] = r_tree.segment(nodes_[j].row, nodes_[j].size);
  for (int j : order_) {
    const Node& n = nodes_[j];
    if (n.clique >= 0) {
      const Clique& cl = cliques_[n.clique];
      for (size_t i = 0; i < n.near.size(); ++i) work_[cl.members[n.near[i]]].noalias() -= n.l[i] * work_[j];
    }
    work_[j] = n.d_inv * work_[j];
  }
  y_tree.resize(tree_rows_);
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    const Node& n = nodes_[*it];
    if (n.clique >= 0) {
      const Clique& cl = cliques_[n.clique];
      for (size_t i = 0; i < n.near.size(); ++i) work_[*it].noalias() -= n.l[i].transpose() * work_[cl.members[n.near[i]]];
    }
    y_tree.segment(n.row, n.size) = work_[*it];
  }
}

Eigen::VectorXd TreeSolver::solve(const Eigen::VectorXd& rhs) const {
  Eigen::VectorXd r_tree(tree_rows_), r_loop(loop_rows_);
  for (int r = 0; r < rhs.size(); ++r) {
    if (tree_row_of_[r] >= 0) r_tree(tree_row_of_[r]) = rhs(r);
    if (loop_row_of_[r] >= 0) r_loop(loop_row_of_[r]) = rhs(r);
  }
  Eigen::VectorXd y_tree;
  treeSolve(r_tree, y_tree);
  Eigen::VectorXd y_loop;
  if (loop_rows_ > 0) {
    // y_l = S^-1 (b_l - A_lt A_tt^-1 b_t),  y_t = A_tt^-1 b_t - G y_l.
    y_loop = schur_.solve(r_loop - a_tl_.transpose() * y_tree);
    y_tree -= g_ * y_loop;
  }
  Eigen::VectorXd y = Eigen::VectorXd::Zero(rhs.size());
  for (int r = 0; r < rhs.size(); ++r) {
    if (tree_row_of_[r] >= 0) y(r) = y_tree(tree_row_of_[r]);
    if (loop_row_of_[r] >= 0) y(r) = y_loop(loop_row_of_[r]);
  }
  return y;
}

}  // namespace ponyhop

#include "physics/featherstone.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <tuple>
#include <type_traits>

#include "physics/featherstone_spatial.h"
#include "physics/hinge_joint.h"
#include "physics/integrator.h"
#include "physics/prismatic_joint.h"
#include "physics/small_matrix.h"
#include "physics/spherical_joint.h"

namespace ponyhop {

// ---------------------------------------------------------------------------------------------
// The tree

// The structure: body count, joint count, which bodies are dynamic, each joint's two bodies.
// Compared in place every step (no allocation); rebuilt only when it changed.
bool ArticulatedSystem::sameSignature(const std::vector<RigidBody>& bodies, const Constraints& joints) const {
  size_t k = 0;
  const auto next = [&](int v) { return k < signature_.size() && signature_[k++] == v; };
  if (!next(static_cast<int>(bodies.size())) || !next(static_cast<int>(joints.size()))) return false;
  for (const RigidBody& b : bodies) {
    if (!next(b.isDynamic() ? 1 : 0)) return false;
  }
  for (const auto& j : joints) {
    if (!next(j->bodyA()) || !next(j->bodyB())) return false;
  }
  return k == signature_.size();
}

Status ArticulatedSystem::build(const std::vector<RigidBody>& bodies, const Constraints& joints) {
  if (sameSignature(bodies, joints)) {
    for (LoopJoint& l : loops_) l.constraint = joints[l.joint].get();
    return built_;
  }
  signature_ = {static_cast<int>(bodies.size()), static_cast<int>(joints.size())};
  for (const RigidBody& b : bodies) signature_.push_back(b.isDynamic() ? 1 : 0);
  for (const auto& j : joints) signature_.insert(signature_.end(), {j->bodyA(), j->bodyB()});
  nodes_.clear();
  dofs_ = 0;
  have_state_ = false;
  composites_formed_ = false;
  const auto fail = [&](std::string e) {
    nodes_.clear();
    built_ =
        Status::error("solver 'featherstone': " + std::move(e) + "; use physics.solver = tree or dense for this scene");
    return built_;
  };
  const auto name = [&](int b) { return b == kWorldBody ? std::string("world") : "'" + bodies[b].name + "'"; };

  const size_t n = bodies.size();
  std::vector<std::vector<std::pair<int, int>>> adjacent(n);  // (joint, other body) between dynamic bodies
  std::vector<int> grounding(n, -1);                          // joint to the world or a prescribed body
  std::vector<char> loop(joints.size(), 0);                   // the joint closes a loop (not in the tree)
  for (size_t j = 0; j < joints.size(); ++j) {
    const Constraint& c = *joints[j];
    if (dynamic_cast<const HingeJoint*>(&c)) {
      loop[j] = 1;  // a hinge is always a loop joint (physics/hinge_joint.h): its rows join the loop rows
      continue;
    }
    if (!dynamic_cast<const SphericalJoint*>(&c) && !dynamic_cast<const PrismaticJoint*>(&c)) {
      return fail("joint " + std::to_string(j) + " ('" + c.typeName() +
                  "') cannot be expressed in reduced coordinates (spherical and prismatic joints only; a contact "
                  "closes a loop through the ground)");
    }
    const int a = c.bodyA(), b = c.bodyB();
    const bool da = dynamicBody(bodies, a), db = dynamicBody(bodies, b);
    if (da && db) {
      adjacent[a].push_back({static_cast<int>(j), b});
      adjacent[b].push_back({static_cast<int>(j), a});
    } else if (da || db) {
      const int body = da ? a : b;
      if (grounding[body] >= 0) {
        loop[j] = 1;  // a second hold of one body: a loop through the world or the prescribed body
      } else {
        grounding[body] = static_cast<int>(j);
      }
    }
  }

  std::vector<char> seen(n, 0);
  std::vector<int> parent_joint(n, -1);
  for (size_t start = 0; start < n; ++start) {
    if (seen[start] || !bodies[start].isDynamic()) continue;
    // The component: its root is the body held by the world / a prescribed body, else the
    // first body (a free-floating base). Two such holds make a loop through the world.
    std::vector<int> component{static_cast<int>(start)};
    seen[start] = 1;
    for (size_t k = 0; k < component.size(); ++k) {
      for (const auto& [j, other] : adjacent[component[k]]) {
        if (!seen[other]) {
          seen[other] = 1;
          component.push_back(other);
        }
      }
    }
    // The first held body (in body order) is the root; every other hold closes a loop.
    int root = component.front(), held = -1;
    for (int b : component) {
      if (grounding[b] < 0) continue;
      if (held >= 0 && b > held) {
        loop[grounding[b]] = 1;
      } else {
        if (held >= 0) loop[grounding[held]] = 1;
        held = root = b;
      }
    }
    for (int b : component) seen[b] = 2;  // 2: in this component, not yet placed

    // Breadth-first from the root: parents before children. A joint that reaches a placed body
    // again closes a loop.
    const size_t first = nodes_.size();
    const auto addNode = [&](int body, int parent, int joint) -> Status {
      Node nd;
      nd.body = body;
      nd.parent = parent;
      nd.dof = dofs_;
      if (dynamicBody(bodies, parent)) {
        for (size_t k = first; k < nodes_.size(); ++k) {
          if (nodes_[k].body == parent) nd.parent_node = static_cast<int>(k);
        }
      }
      const RigidBody& p = bodyOf(bodies, parent);
      const RigidBody& c = bodies[body];
      if (joint < 0) {
        nd.type = Type::Free;
        nd.dofs = 6;
      } else if (const auto* s = dynamic_cast<const SphericalJoint*>(joints[joint].get())) {
        nd.type = Type::Spherical;
        nd.dofs = 3;
        const bool parent_is_a = s->bodyA() == parent && s->bodyB() == body;
        nd.point_parent = parent_is_a ? s->pointA() : s->pointB();
        nd.point_child = parent_is_a ? s->pointB() : s->pointA();
      } else {
        const auto* pj = dynamic_cast<const PrismaticJoint*>(joints[joint].get());
        if (pj->bodyA() != parent) {
          return Status::error("prismatic joint " + std::to_string(joint) + " has its sliding frame on " +
                               name(pj->bodyA()) +
                               ", which is the child here (the frame must be on the parent, the body nearer the root)");
        }
        nd.type = Type::Prismatic;
        nd.dofs = 1;
        // Geometry from the joint as it is now (it holds C = 0): Q0 = q_p^-1 q_c, z and
        // e = R_p^T (x_c - x_p) - s z in the parent's frame, so x_c = x_p + R_p (e + s z).
        const Eigen::Matrix3d rp = p.rotation();
        nd.rest = (p.q.conjugate() * c.q).normalized();
        nd.axis = (rp.transpose() * pj->axis(p)).normalized();
        nd.offset = rp.transpose() * (c.x - p.x) - pj->slide(p, c) * nd.axis;
      }
      dofs_ += nd.dofs;
      nodes_.push_back(nd);
      return {};
    };
    if (Status st = addNode(root,
                            held >= 0 ? (joints[grounding[root]]->bodyA() == root ? joints[grounding[root]]->bodyB()
                                                                                  : joints[grounding[root]]->bodyA())
                                      : kWorldBody,
                            held >= 0 ? grounding[root] : -1);
        !st.ok()) {
      return fail(st.message());
    }
    seen[root] = 1;
    for (size_t k = first; k < nodes_.size(); ++k) {
      const int body = nodes_[k].body;
      for (const auto& [j, other] : adjacent[body]) {
        if (j == parent_joint[body] || loop[j]) continue;
        if (seen[other] == 1) {
          loop[j] = 1;
          continue;
        }
        seen[other] = 1;
        parent_joint[other] = j;
        if (Status st = addNode(other, body, j); !st.ok()) return fail(st.message());
        nodes_[k].children.push_back(static_cast<int>(nodes_.size()) - 1);
      }
    }
  }
  // The loop joints, their rows and the work space of closeLoops() and projectLoops().
  std::vector<int> node_of(n, -1);
  for (size_t i = 0; i < nodes_.size(); ++i) node_of[nodes_[i].body] = static_cast<int>(i);
  const auto nodeOf = [&](int b) { return b == kWorldBody ? -1 : node_of[b]; };
  loops_.clear();
  loop_rows_ = 0;
  for (size_t j = 0; j < joints.size(); ++j) {
    if (!loop[j]) continue;
    LoopJoint l;
    l.joint = static_cast<int>(j);
    l.node_a = nodeOf(joints[j]->bodyA());
    l.node_b = nodeOf(joints[j]->bodyB());
    l.constraint = joints[j].get();
    l.row = loop_rows_;
    l.rows = joints[j]->dimension();
    l.eval.C.resize(l.rows);
    l.eval.ja.resize(l.rows, 6);
    l.eval.jb.resize(l.rows, 6);
    l.eval.bias.resize(l.rows);
    loop_rows_ += l.rows;
    loops_.push_back(l);
  }
  allocate();
  built_ = {};
  return built_;
}

// The work space of the nodes, the loops and the adaptive choice (a step allocates nothing).
void ArticulatedSystem::allocate() {
  for (std::vector<LoopBlock>* v : {&loop_pa_, &loop_u_, &loop_acc_})
    v->assign(nodes_.size(), LoopBlock(6, loop_rows_));
  loop_y_.resize(dofs_, loop_rows_);
  loop_k_.resize(loop_rows_, loop_rows_);
  loop_llt_ = Eigen::LLT<Eigen::MatrixXd>(loop_rows_);
  for (Eigen::VectorXd* v : {&loop_rhs_, &loop_lambda_}) v->setZero(loop_rows_);
  loop_step_.setZero(dofs_);
  coords_.x.assign(nodes_.size(), Eigen::Vector3d::Zero());
  coords_.q.assign(nodes_.size(), Eigen::Quaterniond::Identity());
  coords_.s.assign(nodes_.size(), 0.0);
  u_.setZero(dofs_);
  kin_.resize(nodes_.size());
  frames_.resize(nodes_.size());
  pass_.resize(nodes_.size());
  for (Coordinates* c : {&c0_, &y_, &r_[0], &r_[1], &r_[2], &r_[3]}) *c = coords_;
  for (Eigen::VectorXd* v : {&u0_, &us_, &k_[0], &k_[1], &k_[2], &k_[3], &lock_tau_}) v->setZero(dofs_);
  joint_count_ = 0;
  depth_.assign(nodes_.size(), 0);
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    joint_count_ += nd.type == Type::Free ? 0 : 1;
    if (nd.parent_node >= 0) depth_[i] = depth_[nd.parent_node] + 1;
  }
  rigid_.assign(nodes_.size(), 0);
  active_.assign(nodes_.size(), 1);
  score_.assign(nodes_.size(), 0.0);
  order_.reserve(nodes_.size());
  setAdaptive(budget_, tolerance_);
}

// ---------------------------------------------------------------------------------------------
// Maximal <-> joint coordinates

void ArticulatedSystem::readState(const std::vector<RigidBody>& bodies) {
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    const RigidBody& p = bodyOf(bodies, nd.parent);
    const RigidBody& b = bodies[nd.body];
    switch (nd.type) {
      case Type::Free:
        coords_.x[i] = b.x;
        coords_.q[i] = b.q.normalized();
        u_.segment<3>(nd.dof) = b.v;
        u_.segment<3>(nd.dof + 3) = b.w;
        break;
      case Type::Spherical:
        coords_.q[i] = (p.q.conjugate() * b.q).normalized();
        u_.segment<3>(nd.dof) = p.rotation().transpose() * (b.w - p.w);
        break;
      case Type::Prismatic: {
        const Eigen::Vector3d d = b.x - p.x;
        coords_.s[i] = (p.rotation().transpose() * d - nd.offset).dot(nd.axis);
        u_(nd.dof) = (b.v - p.v - p.w.cross(d)).dot(p.q * nd.axis);
        break;
      }
    }
  }
  have_state_ = true;
}

// Forward kinematics, parents first:
//   spherical: q_i = q_p Q, joint point P = x_p + r_p (r_p = q_p point_p), x_i = P - r_i,
//              w_i = w_p + R_p omega, v_i = v_p + w_p x r_p - w_i x r_i (both ends of the joint
//              move with P);
//   prismatic: q_i = q_p Q0, d = R_p (e + s z), x_i = x_p + d, w_i = w_p, v_i = v_p + w_p x d + s' R_p z.
void ArticulatedSystem::writeState(std::vector<RigidBody>& bodies) const { writeParts<true, true>(bodies); }

// The two halves of writeState(), apart: the poses (and frames_) alone, or the velocities alone
// from the poses and frames_ as they are. The same expressions in the same order as together, so
// writing positions then velocities gives the bodies writeState() gives, bit for bit. The loop
// projection moves the poses with the velocities unused, then u with the poses fixed.
template <bool Positions, bool Velocities>
void ArticulatedSystem::writeParts(std::vector<RigidBody>& bodies) const {
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    const RigidBody& p = bodyOf(bodies, nd.parent);
    RigidBody& b = bodies[nd.body];
    switch (nd.type) {
      case Type::Free:
        if constexpr (Positions) {
          b.x = coords_.x[i];
          b.q = renormalized(coords_.q[i]);
        }
        if constexpr (Velocities) {
          b.v = u_.segment<3>(nd.dof);
          b.w = u_.segment<3>(nd.dof + 3);
        }
        if constexpr (Positions) frames_[i].R = b.q.toRotationMatrix();
        break;
      case Type::Spherical: {
        // Rotation matrices, each built once (parents first: a dynamic parent's is in frames_)
        // and kept for jointKinematics.
        Frame& f = frames_[i];
        // The parent's rotation read where it is (a copy of it into a local was read back across
        // its 16-byte stores: a failed store forwarding, a fifth of this pass's samples), and
        // w_i kept in a local for v_i (read back from b.w, the same stall).
        Eigen::Matrix3d rp_prescribed;
        const Eigen::Matrix3d& rp =
            nd.parent_node >= 0 ? frames_[nd.parent_node].R : (rp_prescribed = p.rotation(), rp_prescribed);
        if constexpr (Positions) {
          b.q = renormalized(p.q * coords_.q[i]);  // one normalization: RK4 stages are not unit
          f.R = b.q.toRotationMatrix();
          f.r_p.noalias() = rp * nd.point_parent;
          f.r_i.noalias() = f.R * nd.point_child;
          b.x = p.x + f.r_p - f.r_i;
        }
        if constexpr (Velocities) {
          const Eigen::Vector3d w = p.w + rp * u_.segment<3>(nd.dof);
          b.w = w;
          b.v = p.v + p.w.cross(f.r_p) - w.cross(f.r_i);
        }
        break;
      }
      case Type::Prismatic: {
        if constexpr (Positions) {
          b.q = renormalized(p.q * nd.rest);
          frames_[i].R = b.q.toRotationMatrix();
        }
        const Eigen::Vector3d d = p.q * (nd.offset + coords_.s[i] * nd.axis);
        if constexpr (Positions) b.x = p.x + d;
        if constexpr (Velocities) {
          b.w = p.w;
          b.v = p.v + p.w.cross(d) + u_(nd.dof) * (p.q * nd.axis);
        }
        break;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Joint kinematics: S and c in A_i = X_i A_p + S_i u' + c_i.
//
// Spherical (r_p = R_p point_p, r_i = R_i point_i, d = x_i - x_p = r_p - r_i, omega in p's frame):
//   w_i = w_p + R_p omega                       => S angular = R_p
//   v_i = v_p + w_p x r_p - w_i x r_i
//       = v_p + w_p x d + r_i x (R_p omega)     => S linear = r_i~ R_p
//   alpha_i = alpha_p + R_p omega' + w_p x (R_p omega)          => c angular = w_p x (R_p omega)
//   a_i = a_p + alpha_p x r_p + w_p x (w_p x r_p) - alpha_i x r_i - w_i x (w_i x r_i)
//       = a_p + alpha_p x d + r_i x (R_p omega') + c linear,
//   c linear = w_p x (w_p x r_p) - w_i x (w_i x r_i) - (c angular) x r_i
//   (the spherical joint's J'q' of physics/spherical_joint.cpp plus the relative term).
// Prismatic (z = R_p z_local, d = x_i - x_p, d' = w_p x d + s' z):
//   w_i = w_p, v_i = v_p + w_p x d + s' z          => S = [z; 0]
//   a_i = a_p + alpha_p x d + w_p x (w_p x d) + 2 s' w_p x z + s'' z
//   c = [w_p x (w_p x d) + 2 s' w_p x z; 0]
// Free root: S = I (u = [v; w]), c = 0.
void ArticulatedSystem::jointKinematics(const std::vector<RigidBody>& bodies, std::vector<Kinematics>& out,
                                        bool written) const {
  out.resize(nodes_.size());
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    const RigidBody& p = bodyOf(bodies, nd.parent);
    const RigidBody& b = bodies[nd.body];
    Kinematics& k = out[i];
    k.R = written ? frames_[i].R : b.rotation();  // writeState()'s, from the q it has just normalized
    k.c.setZero();
    k.a_base.setZero();
    k.d = b.x - p.x;
    switch (nd.type) {
      case Type::Free:
        k.d.setZero();
        k.S = Matrix6::Identity();
        break;
      case Type::Spherical: {
        // Parents come first: a dynamic parent's rotation is already in out.
        k.Rp = nd.parent_node >= 0 ? out[nd.parent_node].R : p.rotation();
        // Read from writeState()'s frames when it has just written them: k.Rp, just copied, was
        // read back across its 16-byte stores (a failed store forwarding, a quarter of this
        // loop's samples).
        const Eigen::Matrix3d& rp = written && nd.parent_node >= 0 ? frames_[nd.parent_node].R : k.Rp;
        const Eigen::Vector3d r_p = written ? frames_[i].r_p : Eigen::Vector3d(rp * nd.point_parent);
        const Eigen::Vector3d r_i = written ? frames_[i].r_i : Eigen::Vector3d(k.R * nd.point_child);
        k.r_i = r_i;
        const Eigen::Vector3d w_rel = rp * u_.segment<3>(nd.dof);
        if (!written) {
          k.S.topLeftCorner<3, 3>() = skew(r_i) * rp;
          k.S.bottomLeftCorner<3, 3>() = rp;
        }
        const Eigen::Vector3d c_ang = p.w.cross(w_rel);
        k.c.head<3>() = p.w.cross(p.w.cross(r_p)) - b.w.cross(b.w.cross(r_i)) - c_ang.cross(r_i);
        k.c.tail<3>() = c_ang;
        break;
      }
      case Type::Prismatic: {
        const Eigen::Vector3d z = p.q * nd.axis;
        k.S.col(0) << z, Eigen::Vector3d::Zero();
        k.c.head<3>() = p.w.cross(p.w.cross(k.d)) + 2.0 * u_(nd.dof) * p.w.cross(z);
        break;
      }
    }
    // A prescribed parent's (or the world's) acceleration is the base acceleration.
    if (nd.type != Type::Free && nd.parent_node < 0) {
      Vector6d ap;
      ap << p.a, p.alpha;
      k.a_base = shiftMotion(k.d, ap);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// ABA (Featherstone 2008; John survey: "a = f + b ... Invert f = I^A a + p^A ... Propagate I^A, p^A
// inward ... Solve for q'' ... Propagate a outward"):
//   pass 1 (forward kinematics): writeState() and jointKinematics().
//   pass 2 (leaves to root): I^A_i = M_i + sum_c X_c^T I^a_c X_c,  p^A_i = b_i + sum_c X_c^T p^a_c,
//     U = I^A S, D = S^T U, u = tau - S^T p^A,
//     I^a = I^A - U D^-1 U^T,  p^a = p^A + I^a c + U D^-1 u.
//   pass 3 (root to leaves): A' = X A_p + c,  u' = D^-1 (u - U^T A'),  A = A' + S u'.
// The joint force on i (from its parent, at i's centre) is F^J_i = I^A_i A_i + p^A_i; a body's
// constraint force is F^J_i - sum_c X_c^T F^J_c.
Eigen::VectorXd ArticulatedSystem::forwardDynamics(std::vector<RigidBody>& bodies, const Eigen::VectorXd& tau) {
  Eigen::VectorXd udot(dofs_);
  aba(bodies, tau.size() == dofs_ ? &tau : nullptr, udot);
  return udot;
}

// Pass 2 for one node with D dofs (fixed sizes: 3 x 3 pivots, 6 x 3 U for a spherical joint).
template <int D>
void ArticulatedSystem::abaInward(size_t r, const Eigen::VectorXd* tau) {
  const Node& nd = nodes_[r];
  const Kinematics& k = kin_[r];
  Pass& p = pass_[r];
  // Spherical: U row-major. It is written row by row and read back by columns of its top
  // half (D_w = U_bottom - r_i~ U_top); column-major, that read took two of its 16-byte stores
  // in one 16-byte load (a failed store forwarding, ~9 % of this pass's samples).
  std::conditional_t<D == 3, Eigen::Matrix<double, 6, 3, Eigen::RowMajor>, Eigen::Matrix<double, 6, D>> U;
  Eigen::Matrix<double, D, D> d;
  Eigen::Matrix<double, D, 1> u;
  if constexpr (D == 3) {
    // Spherical: S = S_w R_p with S_w = [r_i~; I] (the joint's speed in world axes). R_p cancels
    // from U D^-1 U^T and U D^-1 u, so the pass runs on S_w: U_w = I^A S_w = I^A_left r_i~ +
    // I^A_right, D_w = S_w^T U_w = U_w,bottom - r_i~ U_w,top, u_w = R_p u = R_p tau - S_w^T p^A.
    // Half the products of the 6 x 3 S, and R_p only where u' leaves (abaOutward).
    // Products with K = r_i~ as cross products (timesSkew, skewTimes).
    U = timesSkew<6>(p.ia.template leftCols<3>(), k.r_i) + p.ia.template rightCols<3>();
    d = U.template bottomRows<3>() - skewTimes(k.r_i, U.template topRows<3>());
    u = k.r_i.cross(Eigen::Vector3d(p.pa.template head<3>())) - p.pa.template tail<3>();
    if (tau) u.noalias() += k.Rp * tau->segment<3>(nd.dof);
  } else {
    const auto S = k.S.leftCols<D>();
    U.noalias() = p.ia * S;
    d.noalias() = S.transpose() * U;
    u = -S.transpose() * p.pa;
    if (tau) u += tau->segment<D>(nd.dof);
  }
  Eigen::Matrix<double, D, D> dinv;
  if constexpr (D == 3) {
    if (!inverseSpd3(d, dinv)) dinv.setConstant(std::numeric_limits<double>::quiet_NaN());  // reported as non-finite u'
  } else {
    dinv = d.llt().solve(Eigen::Matrix<double, D, D>::Identity());
  }
  p.U.leftCols<D>() = U;
  p.dinv.topLeftCorner<D, D>() = dinv;
  p.u.head<D>() = u;
  if (adaptive_) p.d.topLeftCorner<D, D>() = d;
  if (nd.parent_node < 0) return;
  Pass& parent = pass_[nd.parent_node];
  if (adaptive_ && rigid_[r]) {
    // A rigid joint carries its subtree whole (u' = 0): I^a = I^A, p^a = p^A + I^A c. U, D and
    // u above are kept for the score: the acceleration the joint would take if freed.
    parent.ia += shiftInertia(k.d, p.ia);
    parent.pa += shiftForce(k.d, Vector6d(p.pa + p.ia * k.c));
    return;
  }
  if constexpr (D == 3) {
    // I^a = I^A - U D^-1 U^T annihilates S_w (I^a S_w = U - U D^-1 D = 0): a spherical joint
    // passes no torque about its point P, and I^a is fixed by its top-left block
    // K = A - U_top D^-1 U_top^T (symmetric, by its upper triangle): with r_i,
    //   I^a = [K, -K r_i~; r_i~ K, -r_i~ K r_i~],  I^a c = [t; r_i x t],  t = K (c_lin - r_i x c_ang),
    // and carried to the parent's centre (X^T I^a X, r_i + d = r_p):
    //   [K, -K r_p~; r_p~ K, -r_p~ K r_p~].
    // The same as the 6 x 6 formulas in exact arithmetic, without forming B and E of I^a and
    // shifting them (about a third of this pass's products).
    const auto u_top = U.template topRows<3>();
    const Eigen::Matrix3d ud_top = u_top * dinv;
    Eigen::Matrix3d kk;
    for (int i = 0; i < 3; ++i) {
      for (int j = i; j < 3; ++j) kk(i, j) = kk(j, i) = p.ia(i, j) - ud_top.row(i).dot(u_top.row(j));
    }
    const Eigen::Vector3d& ri = k.r_i;
    const Eigen::Vector3d c_lin = k.c.template head<3>(), c_ang = k.c.template tail<3>();
    const Eigen::Vector3d t = kk * (c_lin - ri.cross(c_ang));
    const Eigen::Vector3d du = dinv * u;
    Vector6d pa_a = p.pa;
    pa_a.noalias() += U * du;
    pa_a.template head<3>() += t;
    pa_a.template tail<3>() += ri.cross(t);
    addShiftedForce(k.d, pa_a, parent.pa);
    const Eigen::Vector3d rp = k.d + ri;
    const Eigen::Matrix3d tr = -timesSkew<3>(kk, rp);  // -K r_p~
    const Eigen::Matrix3d br = skewTimes(rp, tr);      // -r_p~ K r_p~, symmetric: its upper triangle
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        parent.ia(i, j) += kk(i, j);
        parent.ia(i, 3 + j) += tr(i, j);
        parent.ia(3 + j, i) += tr(i, j);
        parent.ia(3 + i, 3 + j) += i <= j ? br(i, j) : br(j, i);
      }
    }
  } else {
    const Eigen::Matrix<double, 6, D> ud = U * dinv;
    const Matrix6 ia_a = p.ia - ud * U.transpose();
    const Vector6d pa_a = p.pa + ia_a * k.c + ud * u;
    parent.ia += shiftInertia(k.d, ia_a);
    parent.pa += shiftForce(k.d, pa_a);
  }
}

// Pass 3 for one node with D dofs.
template <int D>
void ArticulatedSystem::abaOutward(size_t i, Eigen::VectorXd& udot) {
  const Node& nd = nodes_[i];
  const Kinematics& k = kin_[i];
  Pass& p = pass_[i];
  if constexpr (D == 3) {
    // Spherical, world axes (abaInward): u'_w = D^-1 (u - U^T A'), u' = R_p^T u'_w,
    // A = A' + [r_i x u'_w; u'_w]. In scalars, A' included: as a Vector6d, A' was written entry
    // by entry and read back in 16-byte loads (failed store forwarding, a fifth of this
    // pass's samples).
    double a[6];
    if (nd.parent_node >= 0) {  // A' = X A_p + c
      const Vector6d& ap = pass_[nd.parent_node].acc;
      const Eigen::Vector3d& d = k.d;
      a[0] = (ap(0) + (ap(4) * d(2) - ap(5) * d(1))) + k.c(0);
      a[1] = (ap(1) + (ap(5) * d(0) - ap(3) * d(2))) + k.c(1);
      a[2] = (ap(2) + (ap(3) * d(1) - ap(4) * d(0))) + k.c(2);
      for (int j = 3; j < 6; ++j) a[j] = ap(j) + k.c(j);
    } else {
      for (int j = 0; j < 6; ++j) a[j] = k.a_base(j) + k.c(j);
    }
    double v[3];
    for (int j = 0; j < 3; ++j) {
      double uta = p.U(0, j) * a[0];
      for (int m = 1; m < 6; ++m) uta += p.U(m, j) * a[m];
      v[j] = p.u(j) - uta;
    }
    double ud[3];
    for (int m = 0; m < 3; ++m) ud[m] = p.dinv(m, 0) * v[0] + p.dinv(m, 1) * v[1] + p.dinv(m, 2) * v[2];
    if (adaptive_) {
      const Eigen::Vector3d speed = k.Rp * u_.segment<3>(nd.dof);  // world axes, as D
      score<3>(i, speed.data(), ud);
      if (rigid_[i]) {
        udot.segment<3>(nd.dof).setZero();
        for (int j = 0; j < 6; ++j) p.acc(j) = a[j];
        return;
      }
    }
    for (int j = 0; j < 3; ++j) udot(nd.dof + j) = k.Rp(0, j) * ud[0] + k.Rp(1, j) * ud[1] + k.Rp(2, j) * ud[2];
    const Eigen::Vector3d& r = k.r_i;
    p.acc(0) = a[0] + (r(1) * ud[2] - r(2) * ud[1]);
    p.acc(1) = a[1] + (r(2) * ud[0] - r(0) * ud[2]);
    p.acc(2) = a[2] + (r(0) * ud[1] - r(1) * ud[0]);
    p.acc(3) = a[3] + ud[0];
    p.acc(4) = a[4] + ud[1];
    p.acc(5) = a[5] + ud[2];
  } else {
    const Vector6d a_prime = (nd.parent_node >= 0 ? shiftMotion(k.d, pass_[nd.parent_node].acc) : k.a_base) + k.c;
    const Eigen::Matrix<double, D, 1> ud =
        p.dinv.topLeftCorner<D, D>() * (p.u.head<D>() - p.U.leftCols<D>().transpose() * a_prime);
    if (adaptive_ && nd.type != Type::Free) {
      const Eigen::Matrix<double, D, 1> speed = u_.segment<D>(nd.dof);
      score<D>(i, speed.data(), ud.data());
      if (rigid_[i]) {
        udot.segment<D>(nd.dof).setZero();
        p.acc = a_prime;
        return;
      }
    }
    udot.segment<D>(nd.dof) = ud;
    p.acc = a_prime + k.S.leftCols<D>() * ud;
  }
}

void ArticulatedSystem::aba(std::vector<RigidBody>& bodies, const Eigen::VectorXd* tau, Eigen::VectorXd& udot,
                            bool written, bool forces) {
  const size_t n = nodes_.size();
  jointKinematics(bodies, kin_, written);
  for (size_t i = 0; i < n; ++i) writeInertiaAndBias(bodies[nodes_[i].body], kin_[i].R, pass_[i].ia, pass_[i].pa);
  for (size_t r = n; r-- > 0;) {
    dispatch(
        nodes_[r].dofs, [&] { abaInward<1>(r, tau); }, [&] { abaInward<3>(r, tau); }, [&] { abaInward<6>(r, tau); });
  }
  for (size_t i = 0; i < n; ++i) {
    dispatch(
        nodes_[i].dofs, [&] { abaOutward<1>(i, udot); }, [&] { abaOutward<3>(i, udot); },
        [&] { abaOutward<6>(i, udot); });
  }
  loop_failed_ = loop_rows_ > 0 && !closeLoops(bodies, udot);
  if (!forces) {
    // An RK4 stage before the last: the accelerations only (the last stage writes the forces).
    for (size_t i = 0; i < n; ++i) {
      RigidBody& b = bodies[nodes_[i].body];
      b.a = pass_[i].acc.head<3>();
      b.alpha = pass_[i].acc.tail<3>();
    }
    return;
  }
  // Accelerations and constraint forces of the bodies: F^J_i = I^A A + p^A, and a body's
  // constraint force F^J_i - sum_c X_c^T F^J_c (children come after parents: one pass back).
  for (size_t i = 0; i < n; ++i) pass_[i].u = pass_[i].ia * pass_[i].acc + pass_[i].pa;  // u is free now: F^J
  for (size_t i = n; i-- > 0;) {
    const Pass& p = pass_[i];
    RigidBody& b = bodies[nodes_[i].body];
    // fc = F^J_i - sum_c shiftForce(d, f) in scalars: no Vector6d through the stack (a copy of
    // p.u there was read back in 16-byte loads across its 16-byte stores, 11 % of aba's samples).
    double fc[6];
    for (int j = 0; j < 6; ++j) fc[j] = p.u(j);
    for (int c : nodes_[i].children) {
      const Eigen::Vector3d& d = kin_[c].d;
      const Vector6d& f = pass_[c].u;
      fc[0] -= f(0);
      fc[1] -= f(1);
      fc[2] -= f(2);
      fc[3] -= f(3) + (d(1) * f(2) - d(2) * f(1));
      fc[4] -= f(4) + (d(2) * f(0) - d(0) * f(2));
      fc[5] -= f(5) + (d(0) * f(1) - d(1) * f(0));
    }
    b.a = p.acc.head<3>();
    b.alpha = p.acc.tail<3>();
    b.constraint_force = Eigen::Vector3d(fc[0], fc[1], fc[2]);
    b.constraint_torque = Eigen::Vector3d(fc[3], fc[4], fc[5]);
  }
  // A loop joint's force J^T lambda on its dynamic bodies is a constraint force too (ABA took it
  // as an external one).
  for (const LoopJoint& l : loops_) {
    const auto lambda = loop_lambda_.segment(l.row, l.rows);
    for (const auto& [node, j] : {std::pair{l.node_a, &l.eval.ja}, std::pair{l.node_b, &l.eval.jb}}) {
      if (node < 0) continue;
      const Vector6d f = j->transpose() * lambda;
      RigidBody& b = bodies[nodes_[node].body];
      b.constraint_force += f.head<3>();
      b.constraint_torque += f.tail<3>();
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Closed loops (featherstone.h, "Closed loops"; docs/SOLVERS.md)

void ArticulatedSystem::setLoopStabilization(Stabilization stabilization, double baumgarte_alpha,
                                             double baumgarte_beta) {
  loop_stabilization_ = stabilization;
  loop_alpha_ = baumgarte_alpha;
  loop_beta_ = baumgarte_beta;
}

// CRBA (John survey, "Composite Rigid-Body Algorithm"): I^C_i = M_i + sum_c X_c^T I^C_c X_c;
// H_ii = S_i^T I^C_i S_i; then F = I^C_i S_i carried toward the root, F <- X_j^T F, gives
// H_ji = S_j^T F for every ancestor j. H = Phi^T M Phi (Phi: u -> all body twists), so it is
// symmetric positive definite.
Eigen::MatrixXd ArticulatedSystem::massMatrix(const std::vector<RigidBody>& bodies) const {
  const size_t n = nodes_.size();
  std::vector<Kinematics> kin;
  jointKinematics(bodies, kin);
  std::vector<Matrix6> ic(n);
  for (size_t i = 0; i < n; ++i) ic[i] = spatialInertia(bodies[nodes_[i].body]);
  for (size_t r = n; r-- > 0;) {
    if (nodes_[r].parent_node < 0) continue;
    const Matrix6 x = shift(kin[r].d);
    ic[nodes_[r].parent_node] += x.transpose() * ic[r] * x;
  }
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(dofs_, dofs_);
  for (size_t i = 0; i < n; ++i) {
    const Node& ni = nodes_[i];
    Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, 6> f = ic[i] * kin[i].S.leftCols(ni.dofs);
    h.block(ni.dof, ni.dof, ni.dofs, ni.dofs) = kin[i].S.leftCols(ni.dofs).transpose() * f;
    for (int j = static_cast<int>(i); nodes_[j].parent_node >= 0;) {
      f = shift(kin[j].d).transpose() * f;
      j = nodes_[j].parent_node;
      const Node& nj = nodes_[j];
      h.block(nj.dof, ni.dof, nj.dofs, ni.dofs) = kin[j].S.leftCols(nj.dofs).transpose() * f;
      h.block(ni.dof, nj.dof, ni.dofs, nj.dofs) = h.block(nj.dof, ni.dof, nj.dofs, ni.dofs).transpose();
    }
  }
  return h;
}

// Contact impulses in joint space, one row at a time by the articulated inertias (Featherstone
// 2008, ch. 7; Mirtich 1996, "impulse propagation"): the response to a unit impulse is the ABA at
// zero speed with the impulse as the only force. Once per call, inward: the articulated inertias
// I^A_i = M_i + sum_c X_c^T (I^A_c - U_c D_c^-1 U_c^T) X_c, U = I^A S, D = S^T U (no bias: the
// response is linear in the impulse). Per row: p^A = -F on the row's bodies, carried inward along
// their paths to the root only (p^A is zero off them), u = -S^T p^A, p^a = p^A + U D^-1 u; then
// outward over every node, du_i = D^-1 (u_i - U^T A'), A = A' + S du (A' = X A_p, a prescribed
// parent still). O(n) per call plus O(n) per row, against the dense H's O(n^3) Cholesky and
// O(n^2) per row: exactly Phi H^-1 Phi^T J^T in exact arithmetic (physics_tests compare them).
bool ArticulatedSystem::impulseResponse(const std::vector<RigidBody>& bodies, const std::vector<ImpulseRow>& rows,
                                        std::vector<std::vector<Vector6d>>& out) const {
  const size_t n = nodes_.size();
  const size_t m = rows.size();
  if (out.size() < m) out.resize(m);
  ImpulseWork& w = impulse_work_;
  w.node_of.assign(bodies.size(), -1);
  for (size_t i = 0; i < n; ++i) w.node_of[nodes_[i].body] = static_cast<int>(i);
  jointKinematics(bodies, w.kin);
  w.ia.resize(n);
  w.U.resize(n);
  w.dinv.resize(n);
  for (size_t i = 0; i < n; ++i) w.ia[i] = spatialInertia(bodies[nodes_[i].body]);
  for (size_t r = n; r-- > 0;) {
    const Node& nd = nodes_[r];
    const auto S = w.kin[r].S.leftCols(nd.dofs);
    w.U[r].leftCols(nd.dofs).noalias() = w.ia[r] * S;
    const Small d = S.transpose() * w.U[r].leftCols(nd.dofs);
    const Eigen::LLT<Small> llt(d);
    if (llt.info() != Eigen::Success) return false;
    w.dinv[r].topLeftCorner(nd.dofs, nd.dofs) = llt.solve(Small::Identity(nd.dofs, nd.dofs));
    if (nd.parent_node < 0) continue;
    const auto U = w.U[r].leftCols(nd.dofs);
    const Matrix6 ia_a = w.ia[r] - U * w.dinv[r].topLeftCorner(nd.dofs, nd.dofs) * U.transpose();
    w.ia[nd.parent_node] += shiftInertia(w.kin[r].d, ia_a);
  }
  w.pa.assign(n, Vector6d::Zero());
  w.u.assign(n, Vector6d::Zero());
  w.acc.resize(n);
  for (size_t k = 0; k < m; ++k) {
    const ImpulseRow& row = rows[k];
    // The paths from the row's bodies to the root, deepest first (parents come before children).
    w.path.clear();
    for (const auto& [body, wrench] :
         {std::pair<int, Vector6d>{row.a, row.ja}, std::pair<int, Vector6d>{row.b, row.jb}}) {
      if (body < 0 || body >= static_cast<int>(bodies.size()) || w.node_of[body] < 0) continue;
      w.pa[w.node_of[body]] -= wrench;
      for (int j = w.node_of[body]; j >= 0; j = nodes_[j].parent_node) w.path.push_back(j);
    }
    std::sort(w.path.begin(), w.path.end(), std::greater<>());
    w.path.erase(std::unique(w.path.begin(), w.path.end()), w.path.end());
    for (int r : w.path) {
      const Node& nd = nodes_[r];
      const auto S = w.kin[r].S.leftCols(nd.dofs);
      w.u[r].head(nd.dofs).noalias() = -(S.transpose() * w.pa[r]);
      if (nd.parent_node < 0) continue;
      const Vector6d pa_a =
          w.pa[r] + w.U[r].leftCols(nd.dofs) * (w.dinv[r].topLeftCorner(nd.dofs, nd.dofs) * w.u[r].head(nd.dofs));
      addShiftedForce(w.kin[r].d, pa_a, w.pa[nd.parent_node]);
    }
    std::vector<Vector6d>& twists = out[k];
    twists.assign(bodies.size(), Vector6d::Zero());
    for (size_t i = 0; i < n; ++i) {
      const Node& nd = nodes_[i];
      const Vector6d a = nd.parent_node >= 0 ? shiftMotion(w.kin[i].d, w.acc[nd.parent_node]) : Vector6d::Zero();
      const SmallVec du =
          w.dinv[i].topLeftCorner(nd.dofs, nd.dofs) * (w.u[i].head(nd.dofs) - w.U[i].leftCols(nd.dofs).transpose() * a);
      w.acc[i] = a + w.kin[i].S.leftCols(nd.dofs) * du;
      twists[nd.body] = w.acc[i];
    }
    for (int r : w.path) {
      w.pa[r].setZero();
      w.u[r].setZero();
    }
  }
  return true;
}

// The same by the dense H (the reference physics_tests compare impulseResponse() with): tau =
// Phi^T J^T (each row's wrench carried from its body to every joint above it, F_p = X^T F),
// y = H^-1 tau, then the twists Phi y outward (V_i = X_i V_p + S_i y_i, a prescribed parent still).
// O(n^3) per call (H's Cholesky) and O(n^2) per row.
bool ArticulatedSystem::impulseResponseDense(const std::vector<RigidBody>& bodies, const std::vector<ImpulseRow>& rows,
                                             std::vector<std::vector<Vector6d>>& out) const {
  const size_t n = nodes_.size();
  const int m = static_cast<int>(rows.size());
  if (out.size() < rows.size()) out.resize(rows.size());
  std::vector<int> node_of(bodies.size(), -1);
  for (size_t i = 0; i < n; ++i) node_of[nodes_[i].body] = static_cast<int>(i);
  std::vector<Kinematics> kin;
  jointKinematics(bodies, kin);
  const Eigen::LLT<Eigen::MatrixXd> llt(massMatrix(bodies));
  if (llt.info() != Eigen::Success) return false;
  Eigen::MatrixXd tau = Eigen::MatrixXd::Zero(dofs_, m);
  for (int k = 0; k < m; ++k) {
    const ImpulseRow& r = rows[k];
    for (const auto& [body, wrench] : {std::pair<int, Vector6d>{r.a, r.ja}, std::pair<int, Vector6d>{r.b, r.jb}}) {
      if (body < 0 || body >= static_cast<int>(bodies.size()) || node_of[body] < 0) continue;
      const Eigen::Vector3d f = wrench.head<3>();
      for (int j = node_of[body]; j >= 0; j = nodes_[j].parent_node) {
        Vector6d at_j;
        at_j << f, wrench.tail<3>() + (bodies[body].x - bodies[nodes_[j].body].x).cross(f);
        const Node& nj = nodes_[j];
        tau.block(nj.dof, k, nj.dofs, 1) += kin[j].S.leftCols(nj.dofs).transpose() * at_j;
      }
    }
  }
  const Eigen::MatrixXd y = llt.solve(tau);
  std::vector<Vector6d> twist(n);
  for (int k = 0; k < m; ++k) {
    std::vector<Vector6d>& w = out[k];
    w.assign(bodies.size(), Vector6d::Zero());
    for (size_t i = 0; i < n; ++i) {
      const Node& nd = nodes_[i];
      twist[i] = kin[i].S.leftCols(nd.dofs) * y.block(nd.dof, k, nd.dofs, 1);
      if (nd.parent_node >= 0) twist[i] += shiftMotion(kin[i].d, twist[nd.parent_node]);
      w[nd.body] = twist[i];
    }
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Adaptive dynamics (docs/SOLVERS.md, "Adaptive dynamics"; Redon, Galoppo & Lin 2005)

namespace {
// Below this score (J) a joint's motion is round-off: a chain at rest scores ~1e-40 J.
constexpr double kRoundOffScore = 1e-24;
}  // namespace

void ArticulatedSystem::setAdaptive(int budget, double tolerance) {
  budget_ = budget;
  tolerance_ = tolerance;
  const bool on = tolerance > 0.0 || (budget > 0 && budget < joint_count_);
  if (!on) std::fill(rigid_.begin(), rigid_.end(), 0);  // every joint moves (rigid ones at rest relative)
  if (on != adaptive_) composites_formed_ = false;
  adaptive_ = on;
}

// The choice costs an ABA over all n nodes; the step over the composites costs about 4 (k + 1)
// node passes (RK4). Choosing every n / (4 k) steps keeps the choice's share of a step's cost
// at most about the composites' (so the cost per step is O(k) amortized), capped at 16 steps
// so that a joint that starts to matter waits at most that long.
int ArticulatedSystem::choicePeriod() const {
  if (chooser_) return 1;
  const int k = budget_ > 0 ? budget_ : std::max(activeJoints(), 1);
  return std::clamp(joint_count_ / (4 * k), 1, 16);
}

// Candidates: the joints whose depth (joints from the root) is a multiple of n / k, about k of
// them, so every rigid stretch is at least n / k links long (docs/SOLVERS.md, "Adaptive
// dynamics", "Why the candidates are spaced"). A chain in motion everywhere then moves as the
// even split into k stretches; the score drops the joints at rest and chooses among the
// candidates when there are more than k (n / k not whole, trees). Spacing n / (2 k), which left
// the score to pick k of 2 k, made uneven stretches (short ones between long ones): 2 to 4x the
// tip error of the even split over the first second and up to 13x its substeps (a short
// stretch between heavy ones whips).
int ArticulatedSystem::candidateStride() const { return budget_ > 0 ? std::max(1, joint_count_ / budget_) : 1; }

int ArticulatedSystem::activeJoints() const {
  int n = 0;
  for (size_t i = 0; i < nodes_.size(); ++i) n += nodes_[i].type != Type::Free && !rigid_[i] ? 1 : 0;
  return n;
}

std::vector<char> ArticulatedSystem::activeNodes() const {
  std::vector<char> out(nodes_.size());
  for (size_t i = 0; i < nodes_.size(); ++i) out[i] = rigid_[i] ? 0 : 1;
  return out;
}

// score = 1/2 v^T D v + 1/2 h^2 a^T D a: the velocity metric (the kinetic energy of the joint's
// relative motion through the articulated inertia it drives) plus the acceleration metric (the
// energy its acceleration would put into that motion in one step), both in J.
template <int D>
void ArticulatedSystem::score(size_t i, const double* speed, const double* accel) {
  const Matrix6& d = pass_[i].d;
  double sv = 0.0, sa = 0.0;
  for (int a = 0; a < D; ++a) {
    for (int b = 0; b < D; ++b) {
      sv += speed[a] * d(a, b) * speed[b];
      sa += accel[a] * d(a, b) * accel[b];
    }
  }
  score_[i] = 0.5 * (sv + score_h_ * score_h_ * sa);
}

// The inelastic lock (docs/SOLVERS.md): w = the speeds of the joints turning rigid (zero
// elsewhere); the impulses at those joints give du with H du = S_L^T lambda and du_L = -w_L, so
// on the free joints H_FF du_F = (H w)_F. H w by RNEA on the twists Phi w alone (no velocity
// products, no base), then du_F by the ABA of H_FF (the rigid joints carry their subtrees whole,
// no bias). Both O(n), once per switch. Momentum: the impulses are internal to the system.
// Energy: u+ = u + du is H-orthogonal to du (u+_L = 0), so T(u) = T(u+) + 1/2 du^T H du.
void ArticulatedSystem::lock(std::vector<RigidBody>& bodies, const std::vector<char>& active) {
  const size_t n = nodes_.size();
  bool moving = false;
  for (size_t i = 0; i < n; ++i) {
    rigid_[i] = nodes_[i].type != Type::Free && !active[i] ? 1 : 0;
    if (rigid_[i] && !u_.segment(nodes_[i].dof, nodes_[i].dofs).isZero(0.0)) moving = true;
  }
  if (!moving) return;
  jointKinematics(bodies, kin_);  // S (spherical included) and d at the pose the bodies hold
  // Twists Phi w (pass_.acc), then momenta M V carried inward (pass_.pa): (H w)_i = S_i^T F_i.
  for (size_t i = 0; i < n; ++i) {
    const Node& nd = nodes_[i];
    Pass& p = pass_[i];
    p.acc = nd.parent_node >= 0 ? shiftMotion(kin_[i].d, pass_[nd.parent_node].acc) : Vector6d::Zero();
    if (rigid_[i]) p.acc += kin_[i].S.leftCols(nd.dofs) * u_.segment(nd.dof, nd.dofs);
    p.ia = spatialInertia(bodies[nd.body]);
    p.pa = p.ia * p.acc;
  }
  for (size_t r = n; r-- > 0;) {
    const Node& nd = nodes_[r];
    lock_tau_.segment(nd.dof, nd.dofs) = kin_[r].S.leftCols(nd.dofs).transpose() * pass_[r].pa;
    if (nd.parent_node >= 0) addShiftedForce(kin_[r].d, pass_[r].pa, pass_[nd.parent_node].pa);
  }
  // ABA of H_FF du_F = (H w)_F: inward (I^A from the bodies' inertias, p^A from zero) ...
  for (size_t i = 0; i < n; ++i) pass_[i].pa.setZero();
  for (size_t r = n; r-- > 0;) {
    const Node& nd = nodes_[r];
    Pass& p = pass_[r];
    Matrix6 ia = p.ia;
    Vector6d pa = p.pa;
    if (!rigid_[r]) {
      const auto S = kin_[r].S.leftCols(nd.dofs);
      const Small U = p.ia * S;
      const Small dinv = (S.transpose() * U).llt().solve(Small::Identity(nd.dofs, nd.dofs));
      const SmallVec u = lock_tau_.segment(nd.dof, nd.dofs) - S.transpose() * p.pa;
      ia -= U * dinv * U.transpose();
      pa += U * (dinv * u);
      p.U.leftCols(nd.dofs) = U;
      p.dinv.topLeftCorner(nd.dofs, nd.dofs) = dinv;
      p.u.head(nd.dofs) = u;
    }
    if (nd.parent_node < 0) continue;
    pass_[nd.parent_node].ia += shiftInertia(kin_[r].d, ia);
    addShiftedForce(kin_[r].d, pa, pass_[nd.parent_node].pa);
  }
  // ... and outward: du_i = D^-1 (u - U^T A'), A = A' + S du_i; du = -w on the rigid joints.
  for (size_t i = 0; i < n; ++i) {
    const Node& nd = nodes_[i];
    Pass& p = pass_[i];
    const Vector6d a = nd.parent_node >= 0 ? shiftMotion(kin_[i].d, pass_[nd.parent_node].acc) : Vector6d::Zero();
    if (rigid_[i]) {
      u_.segment(nd.dof, nd.dofs).setZero();
      p.acc = a;
      continue;
    }
    const SmallVec du =
        p.dinv.topLeftCorner(nd.dofs, nd.dofs) * (p.u.head(nd.dofs) - p.U.leftCols(nd.dofs).transpose() * a);
    u_.segment(nd.dof, nd.dofs) += du;
    p.acc = a + kin_[i].S.leftCols(nd.dofs) * du;
  }
  writeState(bodies);
}

// Scores at (t, y) from the ABA with the current rigid set (rigid joints: the acceleration they
// would take if freed), then the new set: the joints above the tolerance (or the round-off
// floor), the `budget` highest of them when there are more (nth_element: O(n)). Unchanged, the
// ABA just run is the step's first stage (fresh); changed, the joints turning rigid are locked.
Status ArticulatedSystem::chooseActive(double t, double h, std::vector<RigidBody>& bodies, const ReducedHooks& hooks,
                                       bool& written, bool& fresh) {
  score_h_ = h;
  if (chooser_) {
    // Diagnostics: the full model's u' (every joint free) for the chooser, then its set.
    order_.clear();
    for (size_t i = 0; i < nodes_.size(); ++i) {
      if (rigid_[i]) order_.push_back(static_cast<int>(i));
      rigid_[i] = 0;
    }
    const Status st = derivative(t, coords_, u_, bodies, hooks, k_[0], written);
    for (int i : order_) rigid_[i] = 1;
    if (!st.ok() || stopped_) return st;
    written = true;
    fresh = false;  // k_[0] is the full model's, not the chosen set's
    for (size_t i = 0; i < nodes_.size(); ++i) active_[i] = 0;
    chooser_(t, *this, k_[0], active_);
    for (size_t i = 0; i < nodes_.size(); ++i) active_[i] = nodes_[i].type == Type::Free || active_[i] ? 1 : 0;
    lock(bodies, active_);
    return {};
  }
  if (Status st = derivative(t, coords_, u_, bodies, hooks, k_[0], written); !st.ok() || stopped_) return st;
  written = true;  // the bodies hold (t, y) now
  fresh = true;
  const double floor = std::max(tolerance_, kRoundOffScore);
  const int stride = candidateStride();
  order_.clear();
  for (size_t i = 0; i < nodes_.size(); ++i) {
    if (nodes_[i].type != Type::Free && depth_[i] % stride == 0 && score_[i] > floor) {
      order_.push_back(static_cast<int>(i));
    }
  }
  if (budget_ > 0 && static_cast<int>(order_.size()) > budget_) {
    // Ties by node index, so the choice does not depend on the library's nth_element.
    std::nth_element(order_.begin(), order_.begin() + budget_, order_.end(),
                     [&](int a, int b) { return score_[a] > score_[b] || (score_[a] == score_[b] && a < b); });
    order_.resize(budget_);
  }
  for (size_t i = 0; i < nodes_.size(); ++i) active_[i] = nodes_[i].type == Type::Free ? 1 : 0;
  for (int i : order_) active_[i] = 1;
  bool same = true;
  for (size_t i = 0; i < nodes_.size() && same; ++i) {
    const Node& nd = nodes_[i];
    // A rigid joint that moves again (the bodies were set from outside) is locked again.
    same = (rigid_[i] != 0) == (active_[i] == 0) && (active_[i] || u_.segment(nd.dof, nd.dofs).isZero(0.0));
  }
  if (same) return {};
  lock(bodies, active_);
  fresh = false;  // the first stage again, with the new set (and the new speeds)
  return {};
}

// ---------------------------------------------------------------------------------------------
// Adaptive dynamics over composite bodies (docs/SOLVERS.md, "Adaptive dynamics", "Cost")

// The stretches of the active set: a composite starts at every node whose joint is active, at a
// free root and at a root held rigid to a prescribed parent (welded: it moves with that parent);
// every other node joins its parent's composite. Each composite is one rigid body: its mass, its
// centre and its inertia about the centre are constant in its root link's frame while the
// stretch stays rigid, so they are summed once here (O(n), only when the active set changed) and
// its frame is the principal axes of that inertia, so that it is an ordinary RigidBody. The
// composites' tree is an ArticulatedSystem of its own (sub_) whose joints are the active joints
// with their geometry carried into the composites' frames: the ABA and the integrator then run
// over k + 1 bodies. The bodies must hold the current state (writeState()).
void ArticulatedSystem::formComposites(const std::vector<RigidBody>& bodies) {
  const size_t n = nodes_.size();
  composites_.clear();
  composite_of_.assign(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const Node& nd = nodes_[i];
    if (nd.type != Type::Free && rigid_[i] && nd.parent_node >= 0) {
      composite_of_[i] = composite_of_[nd.parent_node];
      continue;
    }
    Composite c;
    c.node = static_cast<int>(i);
    c.welded = nd.type != Type::Free && rigid_[i];
    composite_of_[i] = static_cast<int>(composites_.size());
    composites_.push_back(c);
  }
  // Members, composite by composite (nodes are parents first, so each list is too).
  composite_nodes_.resize(n);
  std::vector<int>& count = composite_count_;
  count.assign(composites_.size() + 1, 0);
  for (size_t i = 0; i < n; ++i) ++count[composite_of_[i] + 1];
  for (size_t c = 0; c < composites_.size(); ++c) {
    composites_[c].first = count[c];
    count[c + 1] += count[c];
  }
  for (size_t i = 0; i < n; ++i) composite_nodes_[count[composite_of_[i]]++] = static_cast<int>(i);

  if (!sub_) sub_ = std::make_unique<ArticulatedSystem>();
  ArticulatedSystem& sub = *sub_;
  sub.nodes_.clear();
  sub.dofs_ = 0;
  sub_bodies_.clear();
  sub_prescribed_.clear();
  sub_composite_.clear();
  for (Composite& c : composites_) {
    c.count = (&c == &composites_.back() ? static_cast<int>(n) : (&c + 1)->first) - c.first;
    const RigidBody& root = bodies[nodes_[c.node].body];
    RigidBody cb;
    cb.kind = c.welded ? RigidBody::Kind::Kinematic : RigidBody::Kind::Dynamic;
    cb.name = root.name;
    if (c.count == 1) {
      // One link: its own frame and centre (no rounding from an eigen decomposition).
      c.frame.setIdentity();
      c.com.setZero();
      cb.mass = root.mass;
      cb.inertia = root.inertia;
    } else {
      // m, centre and inertia about it in the root's frame: I = sum R_m I_m R_m^T + m (|r|^2 1 - r r^T).
      const Eigen::Quaterniond q_root_inv = root.q.conjugate();
      const Eigen::Matrix3d rt = root.rotation().transpose();
      double mass = 0.0;
      Eigen::Vector3d moment = Eigen::Vector3d::Zero();
      for (int k = 0; k < c.count; ++k) {
        const RigidBody& b = bodies[nodes_[composite_nodes_[c.first + k]].body];
        mass += b.mass;
        moment += b.mass * (rt * (b.x - root.x));
      }
      c.com = moment / mass;
      Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
      for (int k = 0; k < c.count; ++k) {
        const RigidBody& b = bodies[nodes_[composite_nodes_[c.first + k]].body];
        const Eigen::Vector3d r = rt * (b.x - root.x) - c.com;
        inertia += rotateDiagonal((q_root_inv * b.q).normalized().toRotationMatrix(), b.inertia);
        inertia += b.mass * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(inertia);
      Eigen::Matrix3d axes = eig.eigenvectors();
      if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
      c.frame = Eigen::Quaterniond(axes).normalized();
      cb.mass = mass;
      cb.inertia = eig.eigenvalues();
    }
    cb.q = renormalized(root.q * c.frame);
    cb.x = root.x + root.q * c.com;
    cb.w = root.w;
    cb.v = root.v + root.w.cross(cb.x - root.x);
    c.sub_body = static_cast<int>(sub_bodies_.size());
    sub_bodies_.push_back(std::move(cb));
  }
  // The prescribed parents (the anchor, the head) as kinematic bodies of the composites' tree.
  const auto prescribed = [&](int body) {
    if (body == kWorldBody) return kWorldBody;
    for (const auto& [real, in_sub] : sub_prescribed_)
      if (real == body) return in_sub;
    RigidBody copy = bodies[body];
    sub_bodies_.push_back(std::move(copy));
    sub_prescribed_.push_back({body, static_cast<int>(sub_bodies_.size()) - 1});
    return static_cast<int>(sub_bodies_.size()) - 1;
  };
  std::vector<int>& sub_node = composite_count_;  // reused: the composite's node in sub (-1: welded)
  sub_node.assign(composites_.size(), -1);
  for (size_t ci = 0; ci < composites_.size(); ++ci) {
    Composite& c = composites_[ci];
    const Node& nd = nodes_[c.node];
    if (c.welded) {
      // Welded to its prescribed parent B: its pose in B's frame, constant while welded.
      c.base = prescribed(nd.parent);
      const RigidBody& base = bodyOf(sub_bodies_, c.base);
      const RigidBody& cb = sub_bodies_[c.sub_body];
      c.q_parent = (base.q.conjugate() * cb.q).normalized();
      c.x_parent = base.q.conjugate() * (cb.x - base.x);
      continue;
    }
    Node sn;
    sn.type = nd.type;
    sn.dofs = nd.dofs;
    sn.dof = sub.dofs_;
    sn.body = c.sub_body;
    // The parent body's frame in its composite's frame (q', x'; identity for a prescribed parent).
    c.q_parent.setIdentity();
    c.x_parent.setZero();
    if (nd.parent_node >= 0) {
      const Composite& pc = composites_[composite_of_[nd.parent_node]];
      sn.parent = pc.sub_body;
      sn.parent_node = sub_node[composite_of_[nd.parent_node]];
      const RigidBody& pb = bodies[nd.parent];
      const RigidBody& pcb = sub_bodies_[pc.sub_body];
      c.q_parent = (pcb.q.conjugate() * pb.q).normalized();
      c.x_parent = pcb.q.conjugate() * (pb.x - pcb.x);
    } else if (nd.type != Type::Free) {
      sn.parent = prescribed(nd.parent);
    }
    switch (nd.type) {
      case Type::Free:
        break;
      case Type::Spherical:
        sn.point_parent = c.x_parent + c.q_parent * nd.point_parent;
        sn.point_child = c.frame.conjugate() * (nd.point_child - c.com);
        break;
      case Type::Prismatic:
        sn.rest = (c.q_parent * nd.rest * c.frame).normalized();
        sn.axis = c.q_parent * nd.axis;
        sn.offset = c.x_parent + c.q_parent * (nd.offset + nd.rest * c.com);
        break;
    }
    sub.dofs_ += sn.dofs;
    sub_node[ci] = static_cast<int>(sub.nodes_.size());
    sub_composite_.push_back(static_cast<int>(ci));
    if (sn.parent_node >= 0) sub.nodes_[sn.parent_node].children.push_back(sub_node[ci]);
    sub.nodes_.push_back(sn);
  }
  sub.allocate();
  placeWelded(bodies);
  sub.readState(sub_bodies_);
  sub.written_time_ = std::numeric_limits<double>::quiet_NaN();
  composites_formed_ = true;
}

// The composites' tree's kinematic bodies at the time the real prescribed bodies are at: the
// prescribed parents copied, a welded composite carried by its base (x = x_B + R_B x',
// v = v_B + w_B x r, a = a_B + alpha_B x r + w_B x (w_B x r), r = R_B x').
void ArticulatedSystem::placeWelded(const std::vector<RigidBody>& bodies) {
  for (const auto& [real, in_sub] : sub_prescribed_) {
    RigidBody& copy = sub_bodies_[in_sub];
    const RigidBody& b = bodies[real];
    copy.x = b.x;
    copy.q = b.q;
    copy.v = b.v;
    copy.w = b.w;
    copy.a = b.a;
    copy.alpha = b.alpha;
  }
  for (const Composite& c : composites_) {
    if (!c.welded) continue;
    const RigidBody& base = bodyOf(sub_bodies_, c.base);
    RigidBody& cb = sub_bodies_[c.sub_body];
    const Eigen::Vector3d r = base.q * c.x_parent;
    cb.x = base.x + r;
    cb.q = renormalized(base.q * c.q_parent);
    cb.w = base.w;
    cb.v = base.v + base.w.cross(r);
    cb.alpha = base.alpha;
    cb.a = base.a + base.alpha.cross(r) + base.w.cross(base.w.cross(r));
  }
}

// The forces on each composite, sampled once per step at its start (the bodies at t): the sum of
// its links' forces (world) and their torque about its centre, kept in its frame. Held so over
// the step's stages: gravity (m g at the centre, no torque) is exact; a force that depends on
// the state (damping, drag, a spring to a link) is taken at the step's start (first order).
Status ArticulatedSystem::sampleCompositeForces(std::vector<RigidBody>& bodies, const ReducedHooks& hooks) {
  stopped_ = !hooks.forces();
  if (stopped_) return {};
  for (Composite& c : composites_) {
    if (c.welded) continue;
    const RigidBody& cb = sub_bodies_[c.sub_body];
    Eigen::Vector3d f = Eigen::Vector3d::Zero(), t = Eigen::Vector3d::Zero();
    for (int k = 0; k < c.count; ++k) {
      const RigidBody& b = bodies[nodes_[composite_nodes_[c.first + k]].body];
      f += b.force;
      t += b.torque + (b.x - cb.x).cross(b.force);
    }
    c.force = f;
    c.torque = cb.q.conjugate() * t;
  }
  return {};
}

// One step over the composites: the composites' tree steps (its ABA over k + 1 bodies per
// stage), then its state goes back to the active joints' coordinates (the rigid ones have not
// moved relative to their parents) and the links are written from the joint coordinates.
Status ArticulatedSystem::compositeStep(double t, double h, Integrator integrator, std::vector<RigidBody>& bodies,
                                        const ReducedHooks& hooks) {
  if (Status st = sampleCompositeForces(bodies, hooks); !st.ok() || stopped_) return st;
  const ReducedHooks sub_hooks{[&](double time) {
                                 hooks.kinematics(time);
                                 placeWelded(bodies);
                               },
                               [&] {
                                 for (const Composite& c : composites_) {
                                   if (c.welded) continue;
                                   RigidBody& cb = sub_bodies_[c.sub_body];
                                   cb.force = c.force;
                                   cb.torque = cb.q * c.torque;
                                 }
                                 return true;
                               }};
  if (Status st = sub_->step(t, h, integrator, sub_bodies_, sub_hooks); !st.ok()) return st;
  // Back to joint coordinates (the inverse of formComposites()'s carrying of the geometry):
  //   free root:  q_r = q_C F^-1, x_r = x_C - R_r c, v_r = v_C + w x (x_r - x_C);
  //   spherical:  Q = q'^-1 Q_C F^-1, omega = R'^T omega_C;  prismatic: s, s' as they are.
  const ArticulatedSystem& sub = *sub_;
  for (size_t k = 0; k < sub.nodes_.size(); ++k) {
    const Node& sn = sub.nodes_[k];
    const Composite& c = composites_[sub_composite_[k]];
    const Node& nd = nodes_[c.node];
    switch (nd.type) {
      case Type::Free: {
        const RigidBody& cb = sub_bodies_[c.sub_body];
        const Eigen::Quaterniond q = renormalized(cb.q * c.frame.conjugate());
        const Eigen::Vector3d x = cb.x - q * c.com;
        coords_.q[c.node] = q;
        coords_.x[c.node] = x;
        u_.segment<3>(nd.dof) = cb.v + cb.w.cross(x - cb.x);
        u_.segment<3>(nd.dof + 3) = cb.w;
        break;
      }
      case Type::Spherical:
        coords_.q[c.node] = (c.q_parent.conjugate() * sub.coords_.q[k] * c.frame.conjugate()).normalized();
        u_.segment<3>(nd.dof) = c.q_parent.conjugate() * sub.u_.segment<3>(sn.dof);
        break;
      case Type::Prismatic:
        coords_.s[c.node] = sub.coords_.s[k];
        u_(nd.dof) = sub.u_(sn.dof);
        break;
    }
  }
  writeState(bodies);  // the kinematic bodies are at t + h (the composites' step left them there)
  remember(bodies);
  written_time_ = t + h;
  return {};
}

// ---------------------------------------------------------------------------------------------
// Time stepping in joint space

Status ArticulatedSystem::derivative(double t, const Coordinates& c, const Eigen::VectorXd& u,
                                     std::vector<RigidBody>& bodies, const ReducedHooks& hooks, Eigen::VectorXd& udot,
                                     bool written, bool forces) {
  if (!written) {
    if (&c != &coords_) coords_ = c;
    if (&u != &u_) u_ = u;
    hooks.kinematics(t);
    writeState(bodies);
  }
  stopped_ = !hooks.forces();
  if (stopped_) return {};                   // the world stopped itself with its own message
  aba(bodies, nullptr, udot, true, forces);  // the bodies are writeState()'s, here or at the end of the last step
  if (loop_failed_) {
    return Status::error(
        "the loop joints' rows are redundant (the loop-closure matrix L H^-1 L^T is singular): "
        "a loop joint repeats what the tree or another loop joint already holds");
  }
  if (!udot.allFinite()) return Status::error("non-finite joint accelerations");
  return {};
}

// Position rates: x' = v; q' = 1/2 (0, w) q (free, world w); Q' = 1/2 (0, omega) Q (spherical,
// omega in the parent frame); s' = u (prismatic).
void ArticulatedSystem::rates(const Coordinates& c, const Eigen::VectorXd& u, Coordinates& out) const {
  out = c;
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& nd = nodes_[i];
    switch (nd.type) {
      case Type::Free:
        out.x[i] = u.segment<3>(nd.dof);
        out.q[i] = quaternionRate(u.segment<3>(nd.dof + 3), c.q[i]);
        break;
      case Type::Spherical:
        out.q[i] = quaternionRate(u.segment<3>(nd.dof), c.q[i]);
        break;
      case Type::Prismatic:
        out.s[i] = u(nd.dof);
        break;
    }
  }
}

// The coordinates and speeds of the stages live in members sized by build(): equal-size copies
// reuse their storage, so a step allocates nothing.
Status ArticulatedSystem::step(double t, double h, Integrator integrator, std::vector<RigidBody>& bodies,
                               const ReducedHooks& hooks) {
  // Unless someone changed the bodies, they hold what the last step wrote at this very t (its
  // kinematics at t + h, which is this step's t): the first stage skips forward kinematics.
  bool written = have_state_ && t == written_time_ && !bodiesChanged(bodies);
  if (!written) readState(bodies);
  bool fresh = false;  // k_[0] already holds u'(t, y) (adaptive: the choice ran the ABA)
  if (adaptive_) {
    // The choice every choicePeriod() steps (and whenever the bodies were set from outside);
    // the composites re-formed when the active set changed. The step itself is the composites'.
    const bool outside = !written;
    if (outside || !composites_formed_ || --until_choice_ <= 0) {
      if (Status st = chooseActive(t, h, bodies, hooks, written, fresh); !st.ok() || stopped_) return st;
      if (outside || !fresh || !composites_formed_) formComposites(bodies);
      until_choice_ = choicePeriod();
    }
    return compositeStep(t, h, integrator, bodies, hooks);
  }
  const auto axpy = [&](const Coordinates& base, double s, const Coordinates& rate, Coordinates& out) {
    out = base;
    for (size_t i = 0; i < nodes_.size(); ++i) {
      out.x[i] += s * rate.x[i];
      out.q[i].coeffs() += s * rate.q[i].coeffs();
      out.s[i] += s * rate.s[i];
    }
  };
  Eigen::VectorXd* k = k_;
  switch (integrator) {
    case Integrator::SymplecticEuler: {
      // u += h u'(t, y); positions with the new speeds (exact exponential map for rotations).
      // In place: the step needs the coordinates at t only through u'(t, y).
      if (!fresh) {
        if (Status st = derivative(t, coords_, u_, bodies, hooks, k[0], written); !st.ok() || stopped_) return st;
      }
      u_ += h * k[0];
      for (size_t i = 0; i < nodes_.size(); ++i) {
        const Node& nd = nodes_[i];
        switch (nd.type) {
          case Type::Free:
            coords_.x[i] += h * u_.segment<3>(nd.dof);
            coords_.q[i] = renormalized(quaternionFromRotationVector(h * u_.segment<3>(nd.dof + 3)) * coords_.q[i]);
            break;
          case Type::Spherical:
            coords_.q[i] = renormalized(quaternionFromRotationVector(h * u_.segment<3>(nd.dof)) * coords_.q[i]);
            break;
          case Type::Prismatic:
            coords_.s[i] += h * u_(nd.dof);
            break;
        }
      }
      break;
    }
    case Integrator::RK4: {
      // Classical RK4 on (coordinates, u), as physics/rk4.cpp does for bodies: stage quaternions
      // used as they are (normalized when written to bodies), the result renormalized.
      c0_ = coords_;
      u0_ = u_;
      Coordinates* r = r_;
      rates(c0_, u0_, r[0]);
      // The first three stages' bodies are overwritten by the next: their constraint forces are
      // not computed (the same bodies after the step, bit for bit; 2-3 % of an RK4 step).
      if (!fresh) {
        if (Status st = derivative(t, c0_, u0_, bodies, hooks, k[0], written, false); !st.ok() || stopped_) return st;
      }
      axpy(c0_, 0.5 * h, r[0], y_);
      us_ = u0_ + 0.5 * h * k[0];
      rates(y_, us_, r[1]);
      if (Status st = derivative(t + 0.5 * h, y_, us_, bodies, hooks, k[1], false, false); !st.ok() || stopped_)
        return st;
      axpy(c0_, 0.5 * h, r[1], y_);
      us_ = u0_ + 0.5 * h * k[1];
      rates(y_, us_, r[2]);
      if (Status st = derivative(t + 0.5 * h, y_, us_, bodies, hooks, k[2], false, false); !st.ok() || stopped_)
        return st;
      axpy(c0_, h, r[2], y_);
      us_ = u0_ + h * k[2];
      rates(y_, us_, r[3]);
      if (Status st = derivative(t + h, y_, us_, bodies, hooks, k[3]); !st.ok() || stopped_) return st;
      coords_ = c0_;
      for (size_t i = 0; i < nodes_.size(); ++i) {
        coords_.x[i] += h / 6.0 * (r[0].x[i] + 2.0 * r[1].x[i] + 2.0 * r[2].x[i] + r[3].x[i]);
        coords_.q[i].coeffs() +=
            h / 6.0 * (r[0].q[i].coeffs() + 2.0 * r[1].q[i].coeffs() + 2.0 * r[2].q[i].coeffs() + r[3].q[i].coeffs());
        coords_.q[i].normalize();
        coords_.s[i] += h / 6.0 * (r[0].s[i] + 2.0 * r[1].s[i] + 2.0 * r[2].s[i] + r[3].s[i]);
      }
      u_ = u0_ + h / 6.0 * (k[0] + 2.0 * k[1] + 2.0 * k[2] + k[3]);
      break;
    }
    default:
      return Status::error(std::string("solver 'featherstone' integrates in joint space with rk4 or symplectic_euler; "
                                       "physics.integrator = '") +
                           std::string(enumName(integrator)) + "' is not available with it");
  }
  hooks.kinematics(t + h);
  if (loop_rows_ > 0 && loop_stabilization_ == Stabilization::Projection) {
    writeParts<true, false>(bodies);  // the velocities once, at the projected poses
    if (Status st = projectLoops(bodies); !st.ok()) return st;
  } else {
    writeState(bodies);
  }
  remember(bodies);
  written_time_ = t + h;
  return {};
}

Status ArticulatedSystem::evaluate(double t, std::vector<RigidBody>& bodies, const ReducedHooks& hooks) {
  if (!have_state_ || bodiesChanged(bodies)) readState(bodies);
  c0_ = coords_;
  u0_ = u_;
  Status st = derivative(t, c0_, u0_, bodies, hooks, k_[0]);
  remember(bodies);
  return st;
}

// Someone outside (a contact handler, the UI, a test) may set the bodies between steps: then the
// joint coordinates are read again from them (bit-exact comparison with what was written).
bool ArticulatedSystem::bodiesChanged(const std::vector<RigidBody>& bodies) const {
  if (written_.size() != nodes_.size()) return true;
  // Field by field, no 13-vector assembled per body (the same comparison: != on each double).
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const RigidBody& b = bodies[nodes_[i].body];
    const Eigen::Matrix<double, 13, 1>& w = written_[i];
    if (b.x != w.segment<3>(0) || b.q.coeffs() != w.segment<4>(3) || b.v != w.segment<3>(7) || b.w != w.segment<3>(10))
      return true;
  }
  return false;
}

void ArticulatedSystem::remember(const std::vector<RigidBody>& bodies) {
  written_.resize(nodes_.size());
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const RigidBody& b = bodies[nodes_[i].body];
    written_[i] << b.x, b.q.coeffs(), b.v, b.w;
  }
}

// Used by featherstone_loops.cpp (projectLoops) as well as here.
template void ArticulatedSystem::writeParts<true, false>(std::vector<RigidBody>&) const;
template void ArticulatedSystem::writeParts<false, true>(std::vector<RigidBody>&) const;
}  // namespace ponyhop

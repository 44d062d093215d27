// ArticulatedSystem's closed loops (docs/SOLVERS.md): the loop joints' rows solved through the
// ABA's response to unit forces, and their drift projected out. In a file of its own from
// featherstone.cpp: GCC's front end costs more than linearly in one large file of Eigen
// expressions (docs/DEVELOPING.md, compile time).
#include <Eigen/Cholesky>
#include <algorithm>
#include <vector>

#include "physics/featherstone.h"
#include "physics/featherstone_spatial.h"
#include "physics/small_matrix.h"
#include "physics/spherical_joint.h"

namespace ponyhop {

double ArticulatedSystem::evaluateLoops(const std::vector<RigidBody>& bodies) {
  double error = 0.0;
  for (LoopJoint& l : loops_) {
    const Constraint& c = *l.constraint;
    c.evaluate(bodyOf(bodies, c.bodyA()), bodyOf(bodies, c.bodyB()), l.eval);
    error = std::max(error, c.error(l.eval));
  }
  return error;
}

// The ABA's response to unit forces, columns [col, col + m) of the loop rows: row k applies the
// force J_a(k)^T on body a and J_b(k)^T on body b. With no velocity terms, no gravity and no
// base motion, ABA's passes reduce to (the articulated inertias, U and D^-1 are the ABA's):
//   inward:  p^A_i = -F_i + sum_c X_c^T p^a_c,  u = -S^T p^A,  p^a = p^A + U D^-1 u;
//   outward: A' = X A_p (0 at a root),  u' = D^-1 (u - U^T A'),  A = A' + S u'.
// u' of every row is a column of H^-1 L^T (L = J Phi), since ABA solves H u' = tau - C and a force
// F on the bodies is the generalized force Phi^T F. A spherical joint runs in world axes as
// abaInward<3> does: S_w = [r_i~; I], U_w, D_w, and u' = R_p^T u'_w.
namespace {
// Columns [col, col + m) of a 6 x rows block: a fixed 6 x M block when M is (a spherical loop
// joint's three rows, the common case: its products unrolled), else dynamic.
template <int M, class Block>
auto loopCols(Block& b, int col, int m) {
  if constexpr (M == Eigen::Dynamic) {
    return b.middleCols(col, m);
  } else {
    (void)m;
    return b.template middleCols<M>(col);
  }
}
}  // namespace

template <int D, int M>
void ArticulatedSystem::loopInward(size_t r, int col, int m) {
  const Node& nd = nodes_[r];
  const Kinematics& k = kin_[r];
  const Pass& p = pass_[r];
  const auto pa = loopCols<M>(loop_pa_[r], col, m);
  auto u = loopCols<M>(loop_u_[r], col, m).template topRows<D>();
  if constexpr (D == 3) {
    for (int c = 0; c < m; ++c)
      u.col(c) = k.r_i.cross(Eigen::Vector3d(pa.col(c).template head<3>())) - pa.col(c).template tail<3>();
  } else {
    u.noalias() = -k.S.leftCols<D>().transpose() * pa;
  }
  if (nd.parent_node < 0) return;
  // p^a = p^A + U D^-1 u, carried to the parent's centre: X^T p^a.
  Eigen::Matrix<double, 6, M, Eigen::ColMajor, 6, M == Eigen::Dynamic ? 6 : M> f = pa;
  f.noalias() += p.U.leftCols<D>() * (p.dinv.topLeftCorner<D, D>() * u);
  auto parent = loopCols<M>(loop_pa_[nd.parent_node], col, m);
  parent.template topRows<3>() += f.template topRows<3>();
  for (int c = 0; c < m; ++c) {
    const Eigen::Vector3d fl = f.col(c).template head<3>();
    parent.col(c).template tail<3>() += f.col(c).template tail<3>() + k.d.cross(fl);
  }
}

template <int D, int M>
void ArticulatedSystem::loopOutward(size_t i, int col, int m) {
  const Node& nd = nodes_[i];
  const Kinematics& k = kin_[i];
  const Pass& p = pass_[i];
  auto acc = loopCols<M>(loop_acc_[i], col, m);
  const auto u = loopCols<M>(loop_u_[i], col, m).template topRows<D>();
  if (nd.parent_node >= 0) {  // A' = X A_p
    const auto ap = loopCols<M>(loop_acc_[nd.parent_node], col, m);
    acc = ap;
    for (int c = 0; c < m; ++c) {
      const Eigen::Vector3d w = ap.col(c).template tail<3>();
      acc.col(c).template head<3>() += w.cross(k.d);
    }
  } else {
    acc.setZero();
  }
  const Eigen::Matrix<double, D, M, D == 1 ? Eigen::RowMajor : Eigen::ColMajor, D, M == Eigen::Dynamic ? 6 : M> ud =
      p.dinv.topLeftCorner<D, D>() * (u - p.U.leftCols<D>().transpose() * acc);
  if constexpr (D == 3) {
    loopCols<M>(loop_y_, col, m).template middleRows<3>(nd.dof).noalias() = k.Rp.transpose() * ud;
    acc.template bottomRows<3>() += ud;
    for (int c = 0; c < m; ++c) {
      const Eigen::Vector3d w = ud.col(c);
      acc.col(c).template head<3>() += k.r_i.cross(w);
    }
  } else {
    loopCols<M>(loop_y_, col, m).template middleRows<D>(nd.dof) = ud;
    acc.noalias() += k.S.leftCols<D>() * ud;
  }
}

// K lambda = -(J A_0 + J'q' [+ 2 alpha C' + beta^2 C]), with K = J (the bodies' accelerations
// of each row's unit force) = L H^-1 L^T; then u' += H^-1 L^T lambda and, for the bodies and
// their joint forces, A += A(rows) lambda, p^A += p^A(rows) lambda (linear in the forces).
bool ArticulatedSystem::closeLoops(const std::vector<RigidBody>& bodies, Eigen::VectorXd& udot) {
  const size_t n = nodes_.size();
  evaluateLoops(bodies);
  for (size_t i = 0; i < n; ++i) loop_pa_[i].setZero();
  for (const LoopJoint& l : loops_) {
    if (l.node_a >= 0) loop_pa_[l.node_a].middleCols(l.row, l.rows) -= l.eval.ja.transpose();
    if (l.node_b >= 0) loop_pa_[l.node_b].middleCols(l.row, l.rows) -= l.eval.jb.transpose();
  }
  const auto passes = [&]<int M>(const LoopJoint& l) {
    for (size_t r = n; r-- > 0;) {
      dispatch(
          nodes_[r].dofs, [&] { loopInward<1, M>(r, l.row, l.rows); }, [&] { loopInward<3, M>(r, l.row, l.rows); },
          [&] { loopInward<6, M>(r, l.row, l.rows); });
    }
    for (size_t i = 0; i < n; ++i) {
      dispatch(
          nodes_[i].dofs, [&] { loopOutward<1, M>(i, l.row, l.rows); }, [&] { loopOutward<3, M>(i, l.row, l.rows); },
          [&] { loopOutward<6, M>(i, l.row, l.rows); });
    }
  };
  for (const LoopJoint& l : loops_) {
    if (l.rows == 3) {
      passes.template operator()<3>(l);
    } else {
      passes.template operator()<Eigen::Dynamic>(l);
    }
  }
  // K and the right-hand side, joint by joint: the acceleration and velocity of each end (a
  // dynamic body's from the passes, a prescribed body's as prescribed, the world's zero).
  const bool baumgarte = loop_stabilization_ == Stabilization::Baumgarte;
  for (const LoopJoint& l : loops_) {
    auto k = loop_k_.middleRows(l.row, l.rows);
    auto rhs = loop_rhs_.segment(l.row, l.rows);
    k.setZero();
    rhs = l.eval.bias;
    for (const auto& [node, body, j] : {std::tuple{l.node_a, l.constraint->bodyA(), &l.eval.ja},
                                        std::tuple{l.node_b, l.constraint->bodyB(), &l.eval.jb}}) {
      const RigidBody& b = bodyOf(bodies, body);
      Vector6d acc, vel;
      vel << b.v, b.w;
      if (node >= 0) {
        k.noalias() += *j * loop_acc_[node];
        acc = pass_[node].acc;
      } else {
        acc << b.a, b.alpha;
      }
      rhs.noalias() += *j * acc;
      if (baumgarte) rhs.noalias() += 2.0 * loop_alpha_ * (*j * vel);
    }
    if (baumgarte) rhs += loop_beta_ * loop_beta_ * l.eval.C;
  }
  if (loop_rows_ == 3) {  // one spherical loop joint, the common case: fixed-size products and factor
    loop_llt3_.compute(loop_k_.topLeftCorner<3, 3>());
    if (loop_llt3_.info() != Eigen::Success) return false;
    const Eigen::Vector3d lambda = -loop_llt3_.solve(loop_rhs_.head<3>());
    loop_lambda_ = lambda;
    udot.noalias() += loop_y_.leftCols<3>() * lambda;
    for (size_t i = 0; i < n; ++i) {
      pass_[i].acc.noalias() += loop_acc_[i].leftCols<3>() * lambda;
      pass_[i].pa.noalias() += loop_pa_[i].leftCols<3>() * lambda;
    }
    return true;
  }
  loop_llt_.compute(loop_k_);
  if (loop_llt_.info() != Eigen::Success) return false;
  loop_lambda_ = loop_llt_.solve(loop_rhs_);
  loop_lambda_ = -loop_lambda_;
  udot.noalias() += loop_y_ * loop_lambda_;
  for (size_t i = 0; i < n; ++i) {
    pass_[i].acc.noalias() += loop_acc_[i] * loop_lambda_;
    pass_[i].pa.noalias() += loop_pa_[i] * loop_lambda_;
  }
  return true;
}

// out = H^-1 L^T K^-1 rhs with the last closeLoops()'s factor of K (loop_lambda_ = K^-1 rhs).
void ArticulatedSystem::loopCorrection(const Eigen::VectorXd& rhs, Eigen::VectorXd& out) {
  if (loop_rows_ == 3) {
    const Eigen::Vector3d lambda = loop_llt3_.solve(rhs.head<3>());
    loop_lambda_ = lambda;
    out.noalias() = loop_y_.leftCols<3>() * lambda;
  } else {
    loop_lambda_ = loop_llt_.solve(rhs);
    out.noalias() = loop_y_ * loop_lambda_;
  }
}

// Post-stabilization of the loops (as projectPositions/projectVelocities for the multiplier
// solvers, in joint space): dq = -H^-1 L^T K^-1 C applied to the coordinates (a free root's x
// and rotation vector, a spherical joint's rotation vector in the parent's frame, a slide) until
// max |C| <= 1e-12 m, then du = -H^-1 L^T K^-1 (J V) until max |C'| <= 1e-12 m/s (or no longer contracting). H^-1 L^T
// and K are the last closeLoops()'s (the last stage of the step: a chord iteration, converging because they are within
// a step of the pose projected). The metric H makes each correction the smallest change of kinetic energy, as the mass
// metric does for the bodies.
Status ArticulatedSystem::projectLoops(std::vector<RigidBody>& bodies) {
  constexpr double kTolerance = 1e-12;  // m, as projectPositions
  constexpr int kIterations = 20;
  double error = evaluateLoops(bodies);
  for (int it = 0; it < kIterations && error > kTolerance; ++it) {
    for (const LoopJoint& l : loops_) loop_rhs_.segment(l.row, l.rows) = l.eval.C;
    loopCorrection(loop_rhs_, loop_step_);
    for (size_t i = 0; i < nodes_.size(); ++i) {
      const Node& nd = nodes_[i];
      switch (nd.type) {
        case Type::Free:
          coords_.x[i] -= loop_step_.segment<3>(nd.dof);
          coords_.q[i] = renormalized(quaternionFromRotationVector(-loop_step_.segment<3>(nd.dof + 3)) * coords_.q[i]);
          break;
        case Type::Spherical:
          coords_.q[i] = renormalized(quaternionFromRotationVector(-loop_step_.segment<3>(nd.dof)) * coords_.q[i]);
          break;
        case Type::Prismatic:
          coords_.s[i] -= loop_step_(nd.dof);
          break;
      }
    }
    writeParts<true, false>(bodies);
    error = evaluateLoops(bodies);
  }
  writeParts<false, true>(bodies);  // the velocities at the projected poses (the caller wrote the poses alone)
  if (!(error < 1e-6)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "the loop projection left a loop joint open by %.3g m", error);
    return Status::error(buf);
  }
  // C' = J V (a prescribed end moves as prescribed): the velocities are the bodies'.
  double last = std::numeric_limits<double>::infinity();
  for (int it = 0; it < kIterations; ++it) {
    double residual = 0.0;
    for (const LoopJoint& l : loops_) {
      auto r = loop_rhs_.segment(l.row, l.rows);
      r.setZero();
      for (const auto& [body, j] :
           {std::pair{l.constraint->bodyA(), &l.eval.ja}, std::pair{l.constraint->bodyB(), &l.eval.jb}}) {
        const RigidBody& b = bodyOf(bodies, body);
        r.noalias() += j->leftCols<3>() * b.v + j->rightCols<3>() * b.w;
      }
      residual = std::max(residual, r.lpNorm<Eigen::Infinity>());
    }
    // Done at kTolerance (m/s): the chord contracts ~1e-5 a pass here, so the iterations past it only
    // moved u by round-off (the hair loop ran ~4.7 a step to reach 1e-17 m/s, now ~2).
    if (residual <= kTolerance) break;
    if (!(residual < 0.5 * last)) break;  // at round-off: no longer contracting
    last = residual;
    loopCorrection(loop_rhs_, loop_step_);
    u_ -= loop_step_;
    writeParts<false, true>(bodies);  // the poses are as they were
  }
  return {};
}

// RNEA (John survey: "propagate velocities and accelerations outward, forces inward"):
//   A_i = X A_p + S u' + c,  F_i = M_i A_i + b_i + sum_c X_c^T F_c,  tau_i = S^T F_i.
Eigen::VectorXd ArticulatedSystem::inverseDynamics(const std::vector<RigidBody>& bodies,
                                                   const Eigen::VectorXd& udot) const {
  const size_t n = nodes_.size();
  std::vector<Kinematics> kin;
  jointKinematics(bodies, kin);
  std::vector<Vector6d> acc(n), f(n);
  for (size_t i = 0; i < n; ++i) {
    const Node& nd = nodes_[i];
    const Kinematics& k = kin[i];
    acc[i] = (nd.parent_node >= 0 ? shiftMotion(k.d, acc[nd.parent_node]) : k.a_base) + k.c +
             k.S.leftCols(nd.dofs) * udot.segment(nd.dof, nd.dofs);
    f[i] = spatialInertia(bodies[nd.body]) * acc[i] + biasForce(bodies[nd.body]);
  }
  Eigen::VectorXd tau(dofs_);
  for (size_t r = n; r-- > 0;) {
    const Node& nd = nodes_[r];
    tau.segment(nd.dof, nd.dofs) = kin[r].S.leftCols(nd.dofs).transpose() * f[r];
    if (nd.parent_node >= 0) f[nd.parent_node] += shiftForce(kin[r].d, f[r]);
  }
  return tau;
}

}  // namespace ponyhop

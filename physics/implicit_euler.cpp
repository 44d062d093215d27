#include "physics/implicit_euler.h"

#include <Eigen/SparseCore>

#include "physics/sparse_lu.h"

namespace ponyhop {

namespace {

// Accumulated external + controller force of a dynamic body: [force; torque].
Vector6d generalizedForce(const RigidBody& b) {
  Vector6d f;
  f << b.force, b.torque;
  return f;
}

}  // namespace

ConstrainedStepResult linearlyImplicitEulerStep(double t, double h, ConstrainedStep& s) {
  ConstrainedStepResult result;
  std::vector<RigidBody>& bodies = s.bodies;
  std::vector<int> dyn;
  std::vector<int> slot(bodies.size(), -1);
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].isDynamic()) {
      slot[i] = static_cast<int>(dyn.size());
      dyn.push_back(static_cast<int>(i));
    }
  }
  const int nd = static_cast<int>(dyn.size());
  const int nv = 6 * nd;

  // F at the start, and its derivatives by forward differences (a force element that does not
  // depend on a coordinate gives an exact zero, so K and D keep the coupling pattern).
  if (!s.forces(t)) return result;
  Eigen::VectorXd f0(nv);
  for (int k = 0; k < nd; ++k) f0.segment<6>(6 * k) = generalizedForce(bodies[dyn[k]]);
  Eigen::VectorXd gyro = Eigen::VectorXd::Zero(nv);  // -w x (I w), explicit
  for (int k = 0; k < nd; ++k) {
    const RigidBody& b = bodies[dyn[k]];
    gyro.segment<3>(6 * k + 3) = -b.w.cross(b.worldInertia() * b.w);
  }
  std::vector<Eigen::Triplet<double>> kt, dt;
  constexpr double eps = 1e-7;  // m, rad, m/s, rad/s
  Eigen::VectorXd f1(nv);
  for (int k = 0; k < nd; ++k) {
    RigidBody& b = bodies[dyn[k]];
    const RigidBody saved = b;
    for (int j = 0; j < 12; ++j) {
      if (j < 3)
        b.x(j) += eps;
      else if (j < 6)
        b.q = quaternionFromRotationVector(eps * Eigen::Vector3d::Unit(j - 3)) * b.q;
      else if (j < 9)
        b.v(j - 6) += eps;
      else
        b.w(j - 9) += eps;
      if (!s.forces(t)) return result;
      for (int r = 0; r < nd; ++r) f1.segment<6>(6 * r) = generalizedForce(bodies[dyn[r]]);
      const Eigen::VectorXd col = (f1 - f0) / eps;
      auto& out = j < 6 ? kt : dt;
      for (int r = 0; r < nv; ++r) {
        if (col(r) != 0.0) out.emplace_back(r, 6 * k + j % 6, col(r));
      }
      b.x = saved.x;
      b.q = saved.q;
      b.v = saved.v;
      b.w = saved.w;
    }
  }
  if (!s.forces(t)) return result;  // accumulators back at the start state

  // Joints at velocity level with the kinematic bodies' velocities at t + h.
  s.kinematicAt(t + h);
  s.system.evaluate(bodies, s.joints);
  const int m = s.system.rows();
  std::vector<Vector6d> vel(bodies.size());
  Eigen::VectorXd v0(nv);
  for (size_t i = 0; i < bodies.size(); ++i) vel[i] << bodies[i].v, bodies[i].w;
  for (int k = 0; k < nd; ++k) v0.segment<6>(6 * k) = vel[dyn[k]];

  Eigen::SparseMatrix<double> kmat(nv, nv), dmat(nv, nv);
  kmat.setFromTriplets(kt.begin(), kt.end());
  dmat.setFromTriplets(dt.begin(), dt.end());

  std::vector<Eigen::Triplet<double>> a;
  a.reserve(kt.size() + dt.size() + 12 * nd + 12 * m);
  for (int k = 0; k < nd; ++k) {
    const RigidBody& b = bodies[dyn[k]];
    for (int j = 0; j < 3; ++j) a.emplace_back(6 * k + j, 6 * k + j, b.mass);
    const Eigen::Matrix3d inertia = b.worldInertia();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) a.emplace_back(6 * k + 3 + r, 6 * k + 3 + c, inertia(r, c));
  }
  for (const auto& e : kt) a.emplace_back(e.row(), e.col(), -h * h * e.value());
  for (const auto& e : dt) a.emplace_back(e.row(), e.col(), -h * e.value());
  for (const auto& blk : s.system.blocks()) {
    for (const auto& [body, jb] : {std::pair{blk.body_a, &blk.ja}, std::pair{blk.body_b, &blk.jb}}) {
      if (body == kWorldBody || slot[body] < 0) continue;
      for (int r = 0; r < blk.rows; ++r) {
        for (int c = 0; c < 6; ++c) {
          const double v = (*jb)(r, c);
          if (v == 0.0) continue;
          a.emplace_back(nv + blk.row + r, 6 * slot[body] + c, v);  // J
          a.emplace_back(6 * slot[body] + c, nv + blk.row + r, v);  // J^T
        }
      }
    }
  }
  Eigen::SparseMatrix<double> kkt(nv + m, nv + m);
  kkt.setFromTriplets(a.begin(), a.end());
  Eigen::VectorXd rhs(nv + m);
  rhs.head(nv) = h * (f0 + gyro) + h * h * (kmat * v0);
  if (m > 0) rhs.tail(m) = -s.system.times(vel);

  Eigen::VectorXd sol;
  const SparseLuResult solved = sparseLuSolve(kkt, rhs, sol);
  if (solved == SparseLuResult::Singular) {
    result.fail("implicit Euler: the linearized system is singular");
    return result;
  }
  if (solved != SparseLuResult::Solved || !sol.allFinite()) {
    result.fail("implicit Euler: the linear solve failed");
    return result;
  }
  for (int k = 0; k < nd; ++k) {
    RigidBody& b = bodies[dyn[k]];
    b.v += sol.segment<3>(6 * k);
    b.w += sol.segment<3>(6 * k + 3);
    b.x += h * b.v;
    b.q = (quaternionFromRotationVector(h * b.w) * b.q).normalized();
  }
  return result;
}

}  // namespace ponyhop

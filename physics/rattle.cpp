#include "physics/rattle.h"

#include <cmath>
#include <cstdio>

#include "physics/stabilization.h"

namespace ponyhop {

Eigen::Quaterniond freeRotation(const Eigen::Quaterniond& q_in, const Eigen::Vector3d& inertia,
                                const Eigen::Vector3d& L, double h) {
  // An axially symmetric body (two principal inertias equal, I_t, the third I_k about body axis
  // k; the chain's links, the hopper's tubes) or a spherical one: H = |Pi|^2 / (2 I_t) +
  // (1/I_k - 1/I_t) Pi_k^2 / 2. |Pi|^2 commutes with everything, so the two flows commute and
  // their product is the exact flow: a turn about L by h |L| / I_t, then about body axis k by
  // h (1/I_k - 1/I_t) Pi_k, with Pi_k the same before and after the first (a turn about L keeps
  // Pi = R^T L). Two rotations instead of the five of the general splitting below.
  int k = -1;
  if (inertia(1) == inertia(2))
    k = 0;
  else if (inertia(0) == inertia(2))
    k = 1;
  else if (inertia(0) == inertia(1))
    k = 2;
  if (k >= 0) {
    // In scalars: the small vectors stay in registers (no 16-byte reload of values just stored
    // as two 8-byte halves, which stalls).
    const double it = inertia((k + 1) % 3);
    const double a = h / it;
    const double lx = L.x(), ly = L.y(), lz = L.z();
    double ca, sa;
    halfAngleTerms(a * a * (lx * lx + ly * ly + lz * lz), ca, sa);
    const double ux = sa * a * lx, uy = sa * a * ly, uz = sa * a * lz;  // (ca, u): the turn about L
    const double w0 = q_in.w(), x0 = q_in.x(), y0 = q_in.y(), z0 = q_in.z();
    // (ca, u) * q_in
    double w = ca * w0 - ux * x0 - uy * y0 - uz * z0;
    double x = ca * x0 + w0 * ux + uy * z0 - uz * y0;
    double y = ca * y0 + w0 * uy + uz * x0 - ux * z0;
    double z = ca * z0 + w0 * uz + ux * y0 - uy * x0;
    const double c = 1.0 / inertia(k) - 1.0 / it;
    if (c != 0.0) {
      // Pi_k = (R^T L)_k = column k of R(q_in) . L.
      double pk;
      if (k == 0)
        pk = (1.0 - 2.0 * (y0 * y0 + z0 * z0)) * lx + 2.0 * (x0 * y0 + w0 * z0) * ly + 2.0 * (x0 * z0 - w0 * y0) * lz;
      else if (k == 1)
        pk = 2.0 * (x0 * y0 - w0 * z0) * lx + (1.0 - 2.0 * (x0 * x0 + z0 * z0)) * ly + 2.0 * (y0 * z0 + w0 * x0) * lz;
      else
        pk = 2.0 * (x0 * z0 + w0 * y0) * lx + 2.0 * (y0 * z0 - w0 * x0) * ly + (1.0 - 2.0 * (x0 * x0 + y0 * y0)) * lz;
      const double phi = h * c * pk;
      double cb, sb;
      halfAngleTerms(phi * phi, cb, sb);
      const double e = sb * phi;  // (cb, e e_k): the turn about body axis k
      // q * (cb, e e_k)
      const double qw = w, qx = x, qy = y, qz = z;
      if (k == 0) {
        w = cb * qw - e * qx;
        x = cb * qx + e * qw;
        y = cb * qy + e * qz;
        z = cb * qz - e * qy;
      } else if (k == 1) {
        w = cb * qw - e * qy;
        x = cb * qx - e * qz;
        y = cb * qy + e * qw;
        z = cb * qz + e * qx;
      } else {
        w = cb * qw - e * qz;
        x = cb * qx + e * qy;
        y = cb * qy - e * qx;
        z = cb * qz + e * qw;
      }
    }
    return renormalized(Eigen::Quaterniond(w, x, y, z));
  }
  const double c1 = 1.0 / inertia(1) - 1.0 / inertia(0);
  const double c2 = 1.0 / inertia(2) - 1.0 / inertia(0);
  // A(tau): rotate about the world vector L by tau |L| / I_0 (flow of |Pi|^2 / (2 I_0)).
  const auto about_l = [&](const Eigen::Quaterniond& q, double tau) {
    return quaternionFromRotationVector(tau / inertia(0) * L) * q;
  };
  // B, C(tau): rotate about body axis i by tau c_i Pi_i (flow of c_i Pi_i^2 / 2, Pi = R^T L).
  const auto about_axis = [&](const Eigen::Quaterniond& q, int i, double c, double tau) {
    const double pi_i = (q.conjugate() * L)(i);
    return q * quaternionFromRotationVector(tau * c * pi_i * Eigen::Vector3d::Unit(i));
  };
  Eigen::Quaterniond q = about_l(q_in, 0.5 * h);
  q = about_axis(q, 1, c1, 0.5 * h);
  q = about_axis(q, 2, c2, h);
  q = about_axis(q, 1, c1, 0.5 * h);
  return renormalized(about_l(q, 0.5 * h));
}

bool RattleWork::holds(const ConstraintSolver& solver, const std::vector<RigidBody>& bodies,
                       const Constraints& joints) const {
  if (held_generation == 0 || solver.generation() != held_generation || joints.size() != held_joints.size() ||
      bodies.size() != held_x.size())
    return false;
  for (size_t j = 0; j < joints.size(); ++j)
    if (joints[j].get() != held_joints[j]) return false;
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies[i].isDynamic()) continue;
    if (bodies[i].x != held_x[i] || bodies[i].q.coeffs() != held_q[i].coeffs()) return false;
  }
  return true;
}

void RattleWork::remember(const ConstraintSolver& solver, const std::vector<RigidBody>& bodies,
                          const Constraints& joints) {
  held_generation = solver.generation();
  held_joints.resize(joints.size());
  for (size_t j = 0; j < joints.size(); ++j) held_joints[j] = joints[j].get();
  held_x.resize(bodies.size());
  held_q.resize(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) {
    held_x[i] = bodies[i].x;
    held_q[i] = bodies[i].q;
  }
}

ConstrainedStepResult rattleStep(double t, double h, Eigen::VectorXd& mu, ConstrainedStep& s,
                                 const RattleOptions& options) {
  const double tolerance = options.tolerance;
  const int max_iterations = options.max_iterations;
  ConstrainedStepResult result;
  std::vector<RigidBody>& bodies = s.bodies;
  const size_t n = bodies.size();
  RattleWork own;
  RattleWork& work = options.work ? *options.work : own;

  // First kick, known part: forces at (t, q_n, v_n).
  if (!s.forces(t)) return result;
  std::vector<RattleWork::Start>& start = work.start;
  start.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    start[i] = {b.x, b.mass * b.v + 0.5 * h * b.force, b.worldInertia() * b.w + 0.5 * h * b.torque, b.q};
  }
  // J(q_n): the constraint impulse of the first kick acts along the start's Jacobian (SHAKE).
  s.system.evaluate(bodies, s.joints);
  work.jn = s.system;  // same rows as last step: copied into the storage it has
  const ConstraintSystem& jn = work.jn;
  const int rows = jn.rows();
  if (mu.size() != rows) mu.setZero(rows);

  // Positions at t + h for multipliers mu: the first kick with J^T mu, then the drift.
  std::vector<Vector6d>& fc = work.fc;
  fc.resize(n);
  const auto drift = [&](const Eigen::VectorXd& m) {
    std::fill(fc.begin(), fc.end(), Vector6d::Zero());
    if (rows > 0) jn.addTransposeTimes(m, bodies, fc);
    for (size_t i = 0; i < n; ++i) {
      RigidBody& b = bodies[i];
      if (!b.isDynamic()) continue;
      const Eigen::Vector3d p = start[i].p + 0.5 * h * fc[i].head<3>();
      const Eigen::Vector3d l = start[i].l + 0.5 * h * fc[i].tail<3>();
      b.x = start[i].x + h / b.mass * p;
      b.q = freeRotation(start[i].q, b.inertia, l, h);
    }
  };

  // Position multipliers: chord iteration on C(q'(mu)) = 0 (kinematic bodies at t + h).
  s.kinematicAt(t + h);
  const double scale = 2.0 / (h * h);
  double previous = 0.0;
  // The chord matrix: A(q_n) = J(q_n) M^-1 J(q_n)^T, as close to the Newton matrix
  // J(q') M^-1 J(q_n)^T as A(q') is. When the solver still holds the factorization the last
  // step's velocity solve made at these positions (nothing factored or moved since), it is
  // exactly that matrix: no factorization here. Either way the iteration is the same, bit for
  // bit, so the result does not depend on what the solver held.
  if (!work.holds(s.solver, bodies, s.joints) && rows > 0 && !s.solver.factor(bodies, s.system)) {
    result.fail("the constraint matrix J M^-1 J^T is singular");
    return result;
  }
  work.held_generation = 0;
  bool factored = rows > 0;
  for (int k = 0;; ++k) {
    drift(mu);
    s.system.evaluate(bodies, s.joints);
    const double err = s.system.maxError();
    result.iterations = k;
    result.joint_error = err;
    if (!std::isfinite(err)) {
      result.fail("RATTLE position solve produced a non-finite joint error");
      return result;
    }
    if (err <= tolerance) break;
    // Round-off floor: no more progress below 1e-11 m is as good as it gets.
    if (k > 0 && err > 0.5 * previous && err < 1e-11) break;
    if (k >= max_iterations || (k > 3 && err > 0.9 * previous)) {
      result.fail("RATTLE position solve did not converge (joint error %.3g m after %d iterations)", err, k);
      return result;
    }
    // Refactor at the latest iterate unless the last chord step contracted by 4x or better.
    if (!factored || (k > 0 && err > 0.25 * previous)) {
      if (!s.solver.factor(bodies, s.system)) {
        result.fail("the constraint matrix J M^-1 J^T is singular");
        return result;
      }
      factored = true;
    }
    work.rhs = -s.system.C();
    s.solver.solveInto(work.rhs, work.dmu);
    mu += scale * work.dmu;
    previous = err;
  }

  // The world inertia and its inverse at q_{n+1}, once (every use below is at these positions),
  // and the predicted velocity v+ = p+ / m, w+ = I^-1 L+ of the half-step momenta (the first
  // kick's): the positions alone were iterated.
  std::vector<Eigen::Matrix3d>&iw = work.inertia, &iinv = work.inverse_inertia;
  iw.resize(n);
  iinv.resize(n);
  for (size_t i = 0; i < n; ++i) {
    RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    iw[i] = b.worldInertia();
    iinv[i] = b.worldInverseInertia();
    b.v = (start[i].p + 0.5 * h * fc[i].head<3>()) / b.mass;
    b.w = iinv[i] * (start[i].l + 0.5 * h * fc[i].tail<3>());
  }
  // Second kick at (t + h, q_{n+1}) from p+, L+ with the forces at the predicted velocity.
  if (!s.forces(t + h)) return result;
  for (size_t i = 0; i < n; ++i) {
    RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    const Eigen::Vector3d p = start[i].p + 0.5 * h * fc[i].head<3>() + 0.5 * h * b.force;
    const Eigen::Vector3d l = start[i].l + 0.5 * h * fc[i].tail<3>() + 0.5 * h * b.torque;
    b.v = p / b.mass;
    b.w = iinv[i] * l;
  }
  // Velocity multipliers: J(q') v' = -J_k v_k, the mass-metric projection (the impulse
  // h/2 J^T nu changes p and L by exactly that correction).
  if (Status st = projectVelocities(bodies, s.joints, s.system, s.solver, work.projection); !st.ok()) {
    result.fail("RATTLE velocity solve: %s", st.message().c_str());
    return result;
  }
  work.remember(s.solver, bodies, s.joints);  // the factorization of A(q_{n+1})
  if (options.correct_velocity_forces) {
    // One fixed-point iteration of the implicit second kick: F at (t + h, q', v'), the kick
    // redone from p+ with it. The projection is linear and J, A are those of q' (already
    // evaluated and factored by projectVelocities), so the new v' is the old one plus the
    // projected change h/2 M^-1 (F1 - F0): one more solve, no new factorization.
    std::vector<Vector6d>&v1 = work.v1, &f0 = work.f0, &dv = work.dv;
    v1.resize(n);
    f0.resize(n);
    dv.assign(n, Vector6d::Zero());  // zero for kinematic bodies
    for (size_t i = 0; i < n; ++i) {
      v1[i] << bodies[i].v, bodies[i].w;
      f0[i] << bodies[i].force, bodies[i].torque;
    }
    if (!s.forces(t + h)) return result;
    for (size_t i = 0; i < n; ++i) {
      RigidBody& b = bodies[i];
      if (!b.isDynamic()) continue;
      dv[i] << 0.5 * h / b.mass * (b.force - f0[i].head<3>()), iinv[i] * (0.5 * h * (b.torque - f0[i].tail<3>()));
    }
    if (s.system.rows() > 0) {
      // (J M^-1 J^T) y = -J dv: J v' = -J_k v_k held before, so only dv's part is removed.
      massMetricCorrection(bodies, s.system, s.solver, dv, work.projection);
      for (size_t i = 0; i < n; ++i)
        if (bodies[i].isDynamic()) dv[i] += work.projection.dv[i];
    }
    // The iteration contracts by about h/2 |M^-1 dF/dv| per step: the change it makes against
    // the change the first kick made from the predicted velocity v+ (mass metric). At 1 or more
    // (damping too stiff for h) iterating diverges: the step keeps the explicit kick, whose own
    // limit the stability monitor watches. In the asymptotic range the ratio is O(h).
    double change = 0.0, first = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const RigidBody& b = bodies[i];
      if (!b.isDynamic()) continue;
      const Eigen::Vector3d vp = (start[i].p + 0.5 * h * fc[i].head<3>()) / b.mass;
      const Eigen::Vector3d wp = iinv[i] * (start[i].l + 0.5 * h * fc[i].tail<3>());
      const Eigen::Matrix3d& inertia = iw[i];
      const auto norm2 = [&](const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
        return b.mass * v.squaredNorm() + w.dot(inertia * w);
      };
      change += norm2(dv[i].head<3>(), dv[i].tail<3>());
      first += norm2(v1[i].head<3>() - vp, v1[i].tail<3>() - wp);
    }
    if (!std::isfinite(change)) {
      result.fail("RATTLE velocity solve: non-finite velocity correction");
      return result;
    }
    const bool contracts = change < first;
    for (size_t i = 0; i < n; ++i) {
      RigidBody& b = bodies[i];
      if (!b.isDynamic()) continue;
      if (contracts) {
        b.v += dv[i].head<3>();
        b.w += dv[i].tail<3>();
      } else {
        b.force = f0[i].head<3>();  // the explicit kick's forces, for the end point below
        b.torque = f0[i].tail<3>();
      }
    }
    result.corrected = contracts;
  }
  // The step's end point in the bodies' force scratch: the second kick's total force is
  // 2 (p' - p+) / h, its constraint part J(q')^T nu; a and alpha as the joint-force stage
  // writes them (alpha with the gyroscopic term: I^-1 (t - w x I w)).
  for (size_t i = 0; i < n; ++i) {
    RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    const Eigen::Matrix3d& inertia = iw[i];
    const Eigen::Vector3d force = 2.0 / h * (b.mass * b.v - start[i].p) - fc[i].head<3>();
    const Eigen::Vector3d torque = 2.0 / h * (inertia * b.w - start[i].l) - fc[i].tail<3>();
    b.constraint_force = force - b.force;
    b.constraint_torque = torque - b.torque;
    b.a = force / b.mass;
    b.alpha = iinv[i] * (torque - b.w.cross(inertia * b.w));
  }
  return result;
}

}  // namespace ponyhop

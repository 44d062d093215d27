#include "physics/rattle.h"

#include <cmath>
#include <cstdio>

#include "physics/stabilization.h"

namespace ponyhop {

Eigen::Quaterniond freeRotation(const Eigen::Quaterniond& q_in, const Eigen::Vector3d& inertia,
                                const Eigen::Vector3d& L, double h) {
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
  if (c1 != 0.0) q = about_axis(q, 1, c1, 0.5 * h);
  if (c2 != 0.0) q = about_axis(q, 2, c2, h);
  if (c1 != 0.0) q = about_axis(q, 1, c1, 0.5 * h);
  return about_l(q, 0.5 * h).normalized();
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
      b.v = p / b.mass;  // predicted velocity (the second kick's forces)
      b.w = b.worldInverseInertia() * l;
    }
  };

  // Position multipliers: chord iteration on C(q'(mu)) = 0 (kinematic bodies at t + h).
  s.kinematicAt(t + h);
  const double scale = 2.0 / (h * h);
  double previous = 0.0;
  bool factored = false;
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
    if (!factored || err > 0.25 * previous) {
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

  // Second kick at (t + h, q_{n+1}) from the half-step momenta p+, L+ (the first kick's) with
  // the forces at the predicted velocity (drift() left v+ = p+ / m in the bodies).
  if (!s.forces(t + h)) return result;
  for (size_t i = 0; i < n; ++i) {
    RigidBody& b = bodies[i];
    if (!b.isDynamic()) continue;
    const Eigen::Vector3d p = start[i].p + 0.5 * h * fc[i].head<3>() + 0.5 * h * b.force;
    const Eigen::Vector3d l = start[i].l + 0.5 * h * fc[i].tail<3>() + 0.5 * h * b.torque;
    b.v = p / b.mass;
    b.w = b.worldInverseInertia() * l;
  }
  // Velocity multipliers: J(q') v' = -J_k v_k, the mass-metric projection (the impulse
  // h/2 J^T nu changes p and L by exactly that correction).
  if (std::string e = projectVelocities(bodies, s.joints, s.system, s.solver, work.projection); !e.empty()) {
    result.fail("RATTLE velocity solve: %s", e.c_str());
    return result;
  }
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
      dv[i] << 0.5 * h / b.mass * (b.force - f0[i].head<3>()),
          b.worldInverseInertia() * (0.5 * h * (b.torque - f0[i].tail<3>()));
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
      const Eigen::Vector3d wp = b.worldInverseInertia() * (start[i].l + 0.5 * h * fc[i].tail<3>());
      const Eigen::Matrix3d inertia = b.worldInertia();
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
    const Eigen::Matrix3d inertia = b.worldInertia();
    const Eigen::Vector3d force = 2.0 / h * (b.mass * b.v - start[i].p) - fc[i].head<3>();
    const Eigen::Vector3d torque = 2.0 / h * (inertia * b.w - start[i].l) - fc[i].tail<3>();
    b.constraint_force = force - b.force;
    b.constraint_torque = torque - b.torque;
    b.a = force / b.mass;
    b.alpha = b.worldInverseInertia() * (torque - b.w.cross(inertia * b.w));
  }
  return result;
}

}  // namespace ponyhop

#include "physics/prismatic_joint.h"

namespace ponyhop {

// Dot-product row (Hecker lecture, "Rotational Constraints": "what force or torque will enforce this?
// t in direction of t_a x n_b"; "these dot products differentiate with w").
//
//   s fixed in a, t fixed in b (world vectors):  s' = w_a x s,   t' = w_b x t
//   C   = s . t
//   C'  = (w_a x s) . t + s . (w_b x t) = w_a . (s x t) - w_b . (s x t) = (w_a - w_b) . n,
//         n = s x t                                  (triple product: (w x s) . t = w . (s x t))
//   J_a = [ 0  n^T ],   J_b = [ 0  -n^T ]            (no linear columns: a pure torque pair)
//   C'' = (alpha_a - alpha_b) . n + (w_a - w_b) . n',   n' = (w_a x s) x t + s x (w_b x t)
//   J'q' = (w_a - w_b) . ((w_a x s) x t + s x (w_b x t))
//
// J^T lambda is a torque lambda n on a and -lambda n on b: along s x t, as the Hecker lecture says.
JointRow dotRow(const RigidBody& a, const Eigen::Vector3d& s, const RigidBody& b, const Eigen::Vector3d& t) {
  JointRow r;
  const Eigen::Vector3d n = s.cross(t);
  const Eigen::Vector3d dw = a.w - b.w;
  r.C = s.dot(t);
  r.ja.tail<3>() = n.transpose();
  r.jb.tail<3>() = -n.transpose();
  r.bias = dw.dot(a.w.cross(s).cross(t) + s.cross(b.w.cross(t)));
  return r;
}

// Axis row (Hecker lecture: "(R_b - R_a) . n1 = 0 ... forces in direction of n1, n2; n's are local
// coordinate frames; contrast with p_a - p_b = 0"). With points on the axis instead of the
// centres of mass (the same when the centres lie on the axis):
//
//   r_a = p_a - R_a,  r_b = p_b - R_b,  d = p_b - p_a,  u fixed in a:  u' = w_a x u
//   C   = d . u
//   d'  = v_b + w_b x r_b - v_a - w_a x r_a
//   C'  = d' . u + d . (w_a x u)
//       = u . v_b + w_b . (r_b x u) - u . v_a - w_a . (r_a x u) + w_a . (u x d)
//       = u . v_b + w_b . (r_b x u) - u . v_a + w_a . (u x (r_a + d))
//   J_a = [ -u^T   (u x (p_b - R_a))^T ]      (r_a + d = p_b - R_a)
//   J_b = [  u^T   (r_b x u)^T ]
//   C'' = d'' . u + 2 d' . u' + d . u''
//       d'' = a_b + alpha_b x r_b + w_b x (w_b x r_b) - a_a - alpha_a x r_a - w_a x (w_a x r_a)
//       u'' = alpha_a x u + w_a x (w_a x u)
//   J'q' = u . (w_b x (w_b x r_b) - w_a x (w_a x r_a)) + 2 d' . (w_a x u) + d . (w_a x (w_a x u))
//
// J^T lambda: a force lambda u on b at p_b and -lambda u on a at the same point (Newton's third
// law), so the pair exerts no net torque about p_b.
JointRow axisRow(const RigidBody& a, const Eigen::Vector3d& p_a, const Eigen::Vector3d& u, const RigidBody& b,
                 const Eigen::Vector3d& p_b) {
  JointRow r;
  const Eigen::Vector3d r_a = p_a - a.x;
  const Eigen::Vector3d r_b = p_b - b.x;
  const Eigen::Vector3d d = p_b - p_a;
  const Eigen::Vector3d d_dot = b.v + b.w.cross(r_b) - a.v - a.w.cross(r_a);
  const Eigen::Vector3d u_dot = a.w.cross(u);
  r.C = d.dot(u);
  r.ja.head<3>() = -u.transpose();
  r.ja.tail<3>() = u.cross(p_b - a.x).transpose();
  r.jb.head<3>() = u.transpose();
  r.jb.tail<3>() = r_b.cross(u).transpose();
  r.bias =
      u.dot(b.w.cross(b.w.cross(r_b)) - a.w.cross(a.w.cross(r_a))) + 2.0 * d_dot.dot(u_dot) + d.dot(a.w.cross(u_dot));
  return r;
}

void PrismaticJoint::evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const {
  const Eigen::Quaterniond fa = a.q * frame_a_;
  const Eigen::Quaterniond fb = b.q * frame_b_;
  const Eigen::Vector3d xa = fa * Eigen::Vector3d::UnitX(), ya = fa * Eigen::Vector3d::UnitY(),
                        za = fa * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d xb = fb * Eigen::Vector3d::UnitX(), yb = fb * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d pa = a.pointToWorld(point_a_);
  const Eigen::Vector3d pb = b.pointToWorld(point_b_);
  const JointRow rows[5] = {dotRow(a, za, b, xb), dotRow(a, za, b, yb), dotRow(a, xa, b, yb), axisRow(a, pa, xa, b, pb),
                            axisRow(a, pa, ya, b, pb)};
  for (int i = 0; i < 5; ++i) {
    out.C(i) = rows[i].C;
    out.ja.row(i) = rows[i].ja;
    out.jb.row(i) = rows[i].jb;
    out.bias(i) = rows[i].bias;
  }
}

double PrismaticJoint::slide(const RigidBody& a, const RigidBody& b) const {
  return (b.pointToWorld(point_b_) - a.pointToWorld(point_a_)).dot(axis(a));
}

}  // namespace ponyhop

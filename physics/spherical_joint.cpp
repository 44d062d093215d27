#include "physics/spherical_joint.h"

#include "physics/small_matrix.h"

namespace ponyhop {

// Hecker, "How to Simulate a Ponytail" (seed 002, Eq. 1-3, 12-14) and seed 000:
//
//   R_a, R_b   centres of mass (world);   r_a = q_a point_a, r_b = q_b point_b (world-frame arms)
//   p_a = R_a + r_a,  p_b = R_b + r_b     the joint point as seen from each body
//
//   C   = p_a - p_b = R_a + r_a - R_b - r_b                                        (Eq. 13)
//   C'  = R_a' + w_a x r_a - R_b' - w_b x r_b                                     (Eq. 2)
//       = [ I  -r~_a ] [v_a; w_a] + [ -I  r~_b ] [v_b; w_b]      (w x r = -r x w = -r~ w)
//   C'' = R_a'' + alpha_a x r_a + w_a x (w_a x r_a)
//       - R_b'' - alpha_b x r_b - w_b x (w_b x r_b)                                (Eq. 3, 14)
//
// so J_a = [ I  -r~_a ],  J_b = [ -I  r~_b ]  (r~ the cross-product matrix, Hecker's tilde),
// and the velocity-product term J'q' = w_a x (w_a x r_a) - w_b x (w_b x r_b).
// J_a^T lambda = [lambda; r_a x lambda]: Hecker's f_ca = f_c, t_ca = r_a x f_c, with
// lambda = f_c, and -f_c, -r_b x f_c on b (Newton's third law).
void SphericalJoint::evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const {
  const Eigen::Vector3d r_a = rotate(a.q, point_a_);
  const Eigen::Vector3d r_b = rotate(b.q, point_b_);
  out.C = (a.x + r_a) - (b.x + r_b);
  // Written as 3 x 6 through fixed-size maps (the resizes cost nothing: fixed storage).
  out.ja.resize(3, 6);
  out.jb.resize(3, 6);
  Eigen::Map<Eigen::Matrix<double, 3, 6>> ja(out.ja.data()), jb(out.jb.data());
  ja << 1.0, 0.0, 0.0, 0.0, r_a.z(), -r_a.y(),  //
      0.0, 1.0, 0.0, -r_a.z(), 0.0, r_a.x(),    //
      0.0, 0.0, 1.0, r_a.y(), -r_a.x(), 0.0;
  jb << -1.0, 0.0, 0.0, 0.0, -r_b.z(), r_b.y(),  //
      0.0, -1.0, 0.0, r_b.z(), 0.0, -r_b.x(),    //
      0.0, 0.0, -1.0, -r_b.y(), r_b.x(), 0.0;
  out.bias = a.w.cross(a.w.cross(r_a)) - b.w.cross(b.w.cross(r_b));
  out.point = true;
  out.arm_a = r_a;
  out.arm_b = r_b;
}

}  // namespace ponyhop

#include "physics/spherical_joint.h"

#include <limits>

#include "physics/small_matrix.h"

namespace ponyhop {

// Hecker article (Eq. 1-3, 12-14) and Hecker lecture:
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
  // In scalars, written entry by entry (the same operations as the Eigen expressions in the
  // comments): the Vector3d temporaries of the arms and cross products were reread in 16-byte
  // halves of 8-byte stores (failed store forwarding, most of this function's samples).
  const Eigen::Vector3d r_a = rotate(a.q, point_a_);
  const Eigen::Vector3d r_b = rotate(b.q, point_b_);
  const double a0 = r_a(0), a1 = r_a(1), a2 = r_a(2), b0 = r_b(0), b1 = r_b(1), b2 = r_b(2);
  // C = (x_a + r_a) - (x_b + r_b)
  out.C.resize(3);
  out.C(0) = (a.x(0) + a0) - (b.x(0) + b0);
  out.C(1) = (a.x(1) + a1) - (b.x(1) + b1);
  out.C(2) = (a.x(2) + a2) - (b.x(2) + b2);
  // Written as 3 x 6 through fixed-size maps (the resizes cost nothing: fixed storage).
  out.ja.resize(3, 6);
  out.jb.resize(3, 6);
  Eigen::Map<Eigen::Matrix<double, 3, 6>> ja(out.ja.data()), jb(out.jb.data());
  ja << 1.0, 0.0, 0.0, 0.0, a2, -a1,  //
      0.0, 1.0, 0.0, -a2, 0.0, a0,    //
      0.0, 0.0, 1.0, a1, -a0, 0.0;
  jb << -1.0, 0.0, 0.0, 0.0, -b2, b1,  //
      0.0, -1.0, 0.0, b2, 0.0, -b0,    //
      0.0, 0.0, -1.0, -b1, b0, 0.0;
  out.bias.resize(3);
  out.point = true;
  out.arm_a(0) = a0;
  out.arm_a(1) = a1;
  out.arm_a(2) = a2;
  out.arm_b(0) = b0;
  out.arm_b(1) = b1;
  out.arm_b(2) = b2;
  if (!out.bias_wanted) {  // the velocity-level solve never reads J'q'
    out.bias.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  // bias = w_a x (w_a x r_a) - w_b x (w_b x r_b), every entry a named scalar (an array here was
  // stored entry by entry and reread 16 bytes at a time by GCC's vectorizer).
  const double wa0 = a.w(0), wa1 = a.w(1), wa2 = a.w(2), wb0 = b.w(0), wb1 = b.w(1), wb2 = b.w(2);
  const double ca0 = wa1 * a2 - wa2 * a1, ca1 = wa2 * a0 - wa0 * a2, ca2 = wa0 * a1 - wa1 * a0;
  const double cb0 = wb1 * b2 - wb2 * b1, cb1 = wb2 * b0 - wb0 * b2, cb2 = wb0 * b1 - wb1 * b0;
  out.bias(0) = (wa1 * ca2 - wa2 * ca1) - (wb1 * cb2 - wb2 * cb1);
  out.bias(1) = (wa2 * ca0 - wa0 * ca2) - (wb2 * cb0 - wb0 * cb2);
  out.bias(2) = (wa0 * ca1 - wa1 * ca0) - (wb0 * cb1 - wb1 * cb0);
}

}  // namespace ponyhop

// A rigid body in maximal coordinates (Hecker article, Table 1): centre-of-mass position x,
// orientation q (unit quaternion, body to world), linear velocity v, angular velocity w (world
// frame). Dynamic bodies are moved by forces; kinematic bodies follow a prescribed
// KinematicMotion and take no constraint force: their known accelerations enter the
// right-hand side of the constraint equations (Hecker lecture, "Kinematic Control").
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "physics/kinematic.h"

namespace ponyhop {

using Vector6d = Eigen::Matrix<double, 6, 1>;  // [linear; angular], world frame

// The skew (cross-product) matrix: skew(a) b = a x b. Hecker writes it r~.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

// R diag(d) R^T (a principal inertia or its inverse turned to the world frame), symmetric by
// construction: the six upper entries, mirrored.
// Into `out` directly: a returned 3 x 3 written entry by entry and then copied whole is read
// back in 16-byte halves of 8-byte stores (failed store forwarding, a stall per copy).
// In scalars: r is written entry by entry (toRotationMatrix) just before, and Eigen's r * d read
// its columns back 16 bytes at a time (failed store forwarding, the joint-force stage's largest
// stall). The same operations: rd_ik = r_ik d_k, out_ij = rd_i0 r_j0 + (rd_i1 r_j1 + rd_i2 r_j2),
// the order of Eigen's 3-term dot (bit for bit on 2 million random rotations).
inline void rotateDiagonalInto(const Eigen::Matrix3d& r, const Eigen::Vector3d& d, Eigen::Matrix3d& out) {
  double m[3][3], rd[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) m[i][k] = r(i, k);
  }
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) rd[i][k] = m[i][k] * d(k);
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) out(i, j) = out(j, i) = rd[i][0] * m[j][0] + (rd[i][1] * m[j][1] + rd[i][2] * m[j][2]);
  }
}
inline Eigen::Matrix3d rotateDiagonal(const Eigen::Matrix3d& r, const Eigen::Vector3d& d) {
  Eigen::Matrix3d out;
  rotateDiagonalInto(r, d, out);
  return out;
}

// q / |q| for a quaternion that is unit up to round-off (a product of unit quaternions): when
// |q|^2 = 1 + e with |e| < 1e-10, 1 / |q| = 1 - e / 2 + O(e^2) (one Newton step from 1; the
// term left out is below 4e-21), no square root and no division; else q.normalized().
// Always inlined: GCC left it as a call in featherstone.cpp (2 % of its step at N = 8).
[[gnu::always_inline]] inline Eigen::Quaterniond renormalized(const Eigen::Quaterniond& q) {
  const double e = q.squaredNorm() - 1.0;
  if (std::abs(e) < 1e-10) return Eigen::Quaterniond(q.coeffs() * (1.0 - 0.5 * e));
  return q.normalized();
}

// cos(angle / 2) and sin(angle / 2) / angle for angle^2 = angle2: the unit quaternion of a
// rotation vector phi is (c, s phi). Exact for any angle.
inline void halfAngleTerms(double angle2, double& c, double& s) {
  if (angle2 < 1e-2) {
    // A step's turn (angle < 0.1 rad, down to 0: a body at rest; RATTLE's substeps turn about
    // 2 deg): Taylor series in x^2 = angle^2 / 4 (x < 0.05: the first term left out is below
    // 1e-24 relative); no sqrt, sin, cos or division by the angle. Multiplications by the
    // reciprocals: a division by a constant stays a division in IEEE arithmetic.
    const double x2 = 0.25 * angle2;
    constexpr double k12 = 1.0 / 12.0, k30 = 1.0 / 30.0, k56 = 1.0 / 56.0, k90 = 1.0 / 90.0;
    constexpr double k6 = 1.0 / 6.0, k20 = 1.0 / 20.0, k42 = 1.0 / 42.0, k72 = 1.0 / 72.0, k110 = 1.0 / 110.0;
    c = 1.0 - 0.5 * x2 * (1.0 - x2 * k12 * (1.0 - x2 * k30 * (1.0 - x2 * k56 * (1.0 - x2 * k90))));
    s = 0.5 * (1.0 - x2 * k6 * (1.0 - x2 * k20 * (1.0 - x2 * k42 * (1.0 - x2 * k72 * (1.0 - x2 * k110)))));
    return;
  }
  const double angle = std::sqrt(angle2);
  c = std::cos(0.5 * angle);
  s = std::sin(0.5 * angle) / angle;
}

// The unit quaternion of the rotation vector phi (axis * angle), exact for any angle.
inline Eigen::Quaterniond quaternionFromRotationVector(const Eigen::Vector3d& phi) {
  double c, s;
  halfAngleTerms(phi.squaredNorm(), c, s);
  return Eigen::Quaterniond(c, s * phi.x(), s * phi.y(), s * phi.z());
}

// The shortest rotation that turns direction `from` into direction `to` (neither need be unit):
// Eigen's Quaterniond::FromTwoVectors, compiled once, in rigid_body.cpp. Its antiparallel case
// instantiates a JacobiSVD, about 8 s of compiler time in every file that calls it directly.
Eigen::Quaterniond rotationBetween(const Eigen::Vector3d& from, const Eigen::Vector3d& to);

// The rotation vector (axis * angle, angle in [0, pi]) of a unit quaternion.
inline Eigen::Vector3d rotationVector(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // shortest rotation
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();  // small angle: phi ~ 2 sin(phi/2) axis
  return 2.0 * std::atan2(s, q.w()) * q.vec() / s;
}

// What does not change while the world runs: kind, name, mass properties, the prescribed motion.
struct BodyProperties {
  enum class Kind { Dynamic, Kinematic };

  Kind kind = Kind::Dynamic;
  std::string name;                                   // for status messages ("link 3", "head")
  double mass = 1.0;                                  // kg (dynamic bodies)
  Eigen::Vector3d inertia = Eigen::Vector3d::Ones();  // kg m^2, principal, body frame (dynamic bodies)
  KinematicMotion motion;                             // kinematic bodies only
};

// What a step changes: the pose and velocity. Snapshots, restores and the integrators' states are
// vectors of these, copied whole (one assignment per body).
struct BodyState {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();            // m, centre of mass
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // body to world (renormalized after each step)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();            // m/s
  Eigen::Vector3d w = Eigen::Vector3d::Zero();            // rad/s, world frame
};

// What one force evaluation computes from the state (scratch, recomputed every evaluation).
struct BodyForces {
  // Accumulators, world frame, cleared at the start of each force evaluation.
  Eigen::Vector3d force = Eigen::Vector3d::Zero();              // N, external + controller
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();             // N m, about the centre of mass
  Eigen::Vector3d constraint_force = Eigen::Vector3d::Zero();   // N, J^T lambda (linear)
  Eigen::Vector3d constraint_torque = Eigen::Vector3d::Zero();  // N m, J^T lambda (angular)
  // Accelerations, world frame: computed for dynamic bodies (after the joint-force stage),
  // prescribed for kinematic bodies.
  Eigen::Vector3d a = Eigen::Vector3d::Zero();      // m/s^2
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();  // rad/s^2
};

// A body of the world: its properties, its state and its per-evaluation forces, each a part of
// its own (b.x is the state's x; `BodyState& s = b` is the state alone).
struct RigidBody : BodyProperties, BodyState, BodyForces {
  BodyState& state() { return *this; }
  const BodyState& state() const { return *this; }

  bool isDynamic() const { return kind == Kind::Dynamic; }

  Eigen::Matrix3d rotation() const { return renormalized(q).toRotationMatrix(); }
  // I_world = R I_body R^T.
  Eigen::Matrix3d worldInertia() const {
    const Eigen::Matrix3d r = rotation();
    return r * inertia.asDiagonal() * r.transpose();
  }
  Eigen::Matrix3d worldInverseInertia() const {
    const Eigen::Matrix3d r = rotation();
    return r * inertia.cwiseInverse().asDiagonal() * r.transpose();
  }
  // A point fixed in the body: body-frame coordinates to world (Hecker's p = R + r).
  Eigen::Vector3d pointToWorld(const Eigen::Vector3d& body_point) const { return x + q * body_point; }
  // Velocity of the material point at world position p (p' = R' + w x r).
  Eigen::Vector3d velocityAt(const Eigen::Vector3d& p) const { return v + w.cross(p - x); }

  // Acceleration of a free body under the accumulated forces alone (M^-1 F_ext with the
  // gyroscopic term of Euler's equation, t = I alpha + w x (I w)).
  Vector6d freeAcceleration() const {
    const Eigen::Matrix3d r = rotation();
    Vector6d acc;
    freeAcceleration(r, rotateDiagonal(r, inertia.cwiseInverse()), acc);
    return acc;
  }
  // The same from the body's rotation r and world inverse inertia r I^-1 r^T, for a caller that
  // has them already (the joint-force stage builds both once per body and step), into `acc`.
  // Always inlined: as a call, the caller's r and R I^-1 R^T must go through memory, written
  // entry by entry and read back 16 bytes at a time (failed store forwarding).
  // In scalars, the same operations as the Eigen expressions
  //   L = r (I .* (r^T w)),  acc = [F / m; I_w^-1 (T - w x L)]
  // in Eigen's order of the sums: r^T w entry by entry as ((x0 + x1) + x2) (a vectorized dot of
  // r's column), the products M u rows 0 and 1 as ((x0 + x1) + x2) (a packet of two rows) and
  // row 2 as (x0 + (x1 + x2)) (its unrolled scalar sum). r and I_w^-1 were just written entry by
  // entry, and Eigen's products read them back 16 bytes at a time (failed store forwarding, 11 %
  // of the joint-force solve's own samples at N = 8). Every entry the same bits as the Eigen
  // expression's (rigid_body tests).
  [[gnu::always_inline]] void freeAcceleration(const Eigen::Matrix3d& r, const Eigen::Matrix3d& inverse_inertia_world,
                                               Vector6d& acc) const {
    const double w0 = w(0), w1 = w(1), w2 = w(2);
    double u[3];
    for (int k = 0; k < 3; ++k) u[k] = inertia(k) * ((r(0, k) * w0 + r(1, k) * w1) + r(2, k) * w2);
    double l[3];
    for (int i = 0; i < 2; ++i) l[i] = (r(i, 0) * u[0] + r(i, 1) * u[1]) + r(i, 2) * u[2];
    l[2] = r(2, 0) * u[0] + (r(2, 1) * u[1] + r(2, 2) * u[2]);
    const double t0 = torque(0) - (w1 * l[2] - w2 * l[1]);
    const double t1 = torque(1) - (w2 * l[0] - w0 * l[2]);
    const double t2 = torque(2) - (w0 * l[1] - w1 * l[0]);
    for (int i = 0; i < 3; ++i) acc(i) = force(i) / mass;
    const Eigen::Matrix3d& iw = inverse_inertia_world;
    for (int i = 0; i < 2; ++i) acc(3 + i) = (iw(i, 0) * t0 + iw(i, 1) * t1) + iw(i, 2) * t2;
    acc(5) = iw(2, 0) * t0 + (iw(2, 1) * t1 + iw(2, 2) * t2);
  }

  double kineticEnergy() const { return 0.5 * mass * v.squaredNorm() + 0.5 * w.dot(worldInertia() * w); }

  // Kinematic bodies: take the prescribed pose, velocity and acceleration.
  void setKinematicState(const KinematicState& s) {
    x = s.x;
    q = s.q.normalized();
    v = s.v;
    w = s.w;
    a = s.a;
    alpha = s.alpha;
  }
};

}  // namespace ponyhop

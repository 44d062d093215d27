#include "physics/body_pose.h"

#include <algorithm>

namespace ponyhop {
namespace {

// q' = (0, w) q / 2 for a world-frame angular velocity w, as 4-vectors (w, x, y, z).
Eigen::Vector4d quatRate(const Eigen::Quaterniond& q, const Eigen::Vector3d& w) {
  const Eigen::Quaterniond r = Eigen::Quaterniond(0.0, w.x(), w.y(), w.z()) * q;
  return 0.5 * Eigen::Vector4d(r.w(), r.x(), r.y(), r.z());
}

Eigen::Vector4d asVec(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

}  // namespace

void capturePoses(double t, const std::vector<RigidBody>& bodies, PoseFrame& out) {
  out.t = t;
  out.bodies.resize(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) out.bodies[i] = {bodies[i].x, bodies[i].q, bodies[i].v, bodies[i].w};
}

BodyPose interpolatePose(const BodyPose& a, const BodyPose& b, double h, double s) {
  if (s <= 0.0) return a;
  if (s >= 1.0) return b;
  // Cubic Hermite basis and its derivative (d/ds).
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  const double d00 = 6 * s2 - 6 * s, d10 = 3 * s2 - 4 * s + 1, d01 = -6 * s2 + 6 * s, d11 = 3 * s2 - 2 * s;
  BodyPose p;
  p.x = h00 * a.x + h10 * h * a.v + h01 * b.x + h11 * h * b.v;
  p.v = (d00 * a.x + d10 * h * a.v + d01 * b.x + d11 * h * b.v) / h;
  // q and -q are the same rotation: take the end nearer to a.
  const Eigen::Vector4d qa = asVec(a.q);
  Eigen::Vector4d qb = asVec(b.q);
  Eigen::Vector4d rb = quatRate(b.q, b.w);
  if (qa.dot(qb) < 0.0) {
    qb = -qb;
    rb = -rb;
  }
  const Eigen::Vector4d ra = quatRate(a.q, a.w);
  const Eigen::Vector4d qr = h00 * qa + h10 * h * ra + h01 * qb + h11 * h * rb;
  const Eigen::Vector4d dr = (d00 * qa + d10 * h * ra + d01 * qb + d11 * h * rb) / h;
  const double n2 = qr.squaredNorm();
  const Eigen::Quaterniond q_raw(qr[0], qr[1], qr[2], qr[3]);
  p.q = q_raw.normalized();
  // Angular velocity of the normalized curve: w = 2 vec(q_raw' conj(q_raw)) / |q_raw|^2.
  const Eigen::Quaterniond dq(dr[0], dr[1], dr[2], dr[3]);
  p.w = 2.0 * (dq * q_raw.conjugate()).vec() / n2;
  return p;
}

PoseFrame interpolatePoses(const PoseFrame& a, const PoseFrame& b, double t) {
  const double h = b.t - a.t;
  if (!(h > 0.0)) return b;
  const double s = std::clamp((t - a.t) / h, 0.0, 1.0);
  PoseFrame f;
  f.t = t;
  f.bodies.resize(a.bodies.size());
  for (size_t i = 0; i < a.bodies.size(); ++i) f.bodies[i] = interpolatePose(a.bodies[i], b.bodies[i], h, s);
  return f;
}

}  // namespace ponyhop

// A bilateral (equality) constraint C(q) = 0 between two bodies, in maximal coordinates
// (Hecker lecture, "Math to the Rescue"):
//
//   C(q) = 0,   C' = J q' = 0,   C'' = J q'' + J' q' = 0,
//   q'' = M^-1 (F_ext + J^T lambda)   =>   (J M^-1 J^T) lambda = -J' q' - J M^-1 F_ext.
//
// Here q' of one body is its 6-vector [v; w] (world frame) and q'' is [a; alpha], so a
// constraint of dimension m fills, for the current state:
//   C     (m)       the error (a spherical joint: the gap between its two points, metres),
//   J_a   (m x 6)   dC'/d[v_a; w_a]   (columns: linear, then angular; world frame),
//   J_b   (m x 6)   dC'/d[v_b; w_b],
//   bias  (m)       J' q', the velocity-product term, so that C'' = J_a acc_a + J_b acc_b + bias.
// Either body may be kinematic (its acceleration is known and moves to the right-hand side) or
// kWorldBody (fixed at the origin). New joint types (the hopper's prismatic knee: 3 rotational
// dot-product rows + 2 translational rows) subclass Constraint; solvers see only the rows.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "physics/rigid_body.h"

namespace ponyhop {

inline constexpr int kWorldBody = -1;  // "the world": a fixed frame at the origin

// m x 6 with m <= 6: no heap allocation per evaluation.
using JacobianBlock = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::ColMajor, 6, 6>;
using ConstraintVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 6, 1>;

struct ConstraintRows {
  ConstraintVector C;
  JacobianBlock ja;
  JacobianBlock jb;
  ConstraintVector bias;  // J' q'
  // A point joint (3 rows, a point of a on a point of b) may say so: then J_a = [I, -arm_a~] and
  // J_b = [-I, arm_b~] with the world-frame arms from each centre, and the solvers use that
  // structure (J x = v_a + w_a x arm_a - ..., J M^-1 J^T by cross products) instead of the
  // general 3 x 6 blocks. ConstraintSystem::evaluate clears it before each evaluate().
  bool point = false;
  // Set by the caller: false when nothing will read J'q' (a joint may then leave it NaN).
  bool bias_wanted = true;
  Eigen::Vector3d arm_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d arm_b = Eigen::Vector3d::Zero();
};

class Constraint {
 public:
  Constraint(int body_a, int body_b) : body_a_(body_a), body_b_(body_b) {}
  virtual ~Constraint() = default;

  virtual int dimension() const = 0;
  virtual const char* typeName() const = 0;
  // Fill C, J_a, J_b and J'q' for the current states of a and b (worldBody() for kWorldBody).
  virtual void evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const = 0;
  // The joint's error for reports: |C| (metres for position rows).
  virtual double error(const ConstraintRows& rows) const { return rows.C.norm(); }
  // evaluate() into rows sized by dimension(): for reports and tests (the solvers reuse theirs).
  ConstraintRows rowsAt(const RigidBody& a, const RigidBody& b) const {
    ConstraintRows r;
    const int m = dimension();
    r.C.resize(m);
    r.ja.resize(m, 6);
    r.jb.resize(m, 6);
    r.bias.resize(m);
    evaluate(a, b, r);
    return r;
  }

  int bodyA() const { return body_a_; }
  int bodyB() const { return body_b_; }

 private:
  int body_a_;
  int body_b_;
};

using Constraints = std::vector<std::unique_ptr<Constraint>>;

// The fixed world frame as a (kinematic) body at rest at the origin.
const RigidBody& worldBody();
// Body i of `bodies`, or the world's body for kWorldBody; whether body i moves under forces.
inline const RigidBody& bodyOf(const std::vector<RigidBody>& bodies, int i) {
  return i == kWorldBody ? worldBody() : bodies[size_t(i)];
}
inline bool dynamicBody(const std::vector<RigidBody>& bodies, int i) {
  return i != kWorldBody && bodies[size_t(i)].isDynamic();
}

// All constraints of a world evaluated at one state: stacked C, J'q' and the Jacobian blocks
// (J itself is never stored: each row block touches at most two bodies).
class ConstraintSystem {
 public:
  // A joint's rows as its evaluate() wrote them (C, J_a, J_b, J'q' and, for a point joint, its
  // arms: ja = [I, -arm_a~], jb = [-I, arm_b~]), where they sit in the stacked system, and
  // between which bodies.
  struct Block : ConstraintRows {
    int body_a = kWorldBody;
    int body_b = kWorldBody;
    int row = 0;                             // first row in the stacked system
    int rows = 0;                            // the constraint's dimension
    const Constraint* constraint = nullptr;  // the joint that wrote it (for maxError())
  };

  // with_bias = false: J'q' only where a joint needs no work for it, NaN where it skipped it (a
  // point joint): for a solve that never reads bias() (stabilization = velocity).
  void evaluate(const std::vector<RigidBody>& bodies, const Constraints& constraints, bool with_bias = true);

  int rows() const { return rows_; }
  const std::vector<Block>& blocks() const { return blocks_; }
  const Eigen::VectorXd& C() const { return c_; }
  const Eigen::VectorXd& bias() const { return bias_; }
  // max over joints of |C_j| (each joint's own error measure), computed on the first call after
  // evaluate() (a norm and a virtual call per joint that the joint-force stage never needs). The
  // constraints given to evaluate() must still exist.
  double maxError() const;

  // J x for one 6-vector per body (x of kinematic bodies counts; the world's is zero).
  Eigen::VectorXd times(const std::vector<Vector6d>& per_body) const;
  // out = J x (out resized to rows() when needed).
  void timesInto(const std::vector<Vector6d>& per_body, Eigen::VectorXd& out) const;
  // The same, and out_velocity = J q' for the bodies' velocities (v; w) in the same pass: the
  // values of timesInto with a vector of (v; w) per body, without building it.
  void timesInto(const std::vector<Vector6d>& per_body, const std::vector<RigidBody>& bodies, Eigen::VectorXd& out,
                 Eigen::VectorXd& out_velocity) const;
  // out[body] += J^T lambda for dynamic bodies only (kinematic bodies take no constraint force).
  void addTransposeTimes(const Eigen::VectorXd& lambda, const std::vector<RigidBody>& bodies,
                         std::vector<Vector6d>& out) const;

 private:
  std::vector<Block> blocks_;
  Eigen::VectorXd c_;
  Eigen::VectorXd bias_;
  int rows_ = 0;
  mutable double max_error_ = 0.0;
  mutable bool max_error_known_ = true;
};

}  // namespace ponyhop

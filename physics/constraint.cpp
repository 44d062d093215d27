#include "physics/constraint.h"

namespace ponyhop {

const RigidBody& worldBody() {
  static const RigidBody world = [] {
    RigidBody b;
    b.kind = RigidBody::Kind::Kinematic;
    b.name = "world";
    return b;
  }();
  return world;
}

void ConstraintSystem::evaluate(const std::vector<RigidBody>& bodies, const Constraints& constraints, bool with_bias) {
  const auto bodyOf = [&](int i) -> const RigidBody& { return i == kWorldBody ? worldBody() : bodies[i]; };
  rows_ = 0;
  for (const auto& c : constraints) rows_ += c->dimension();
  blocks_.resize(constraints.size());
  c_.resize(rows_);
  bias_.resize(rows_);
  max_error_ = 0.0;
  max_error_known_ = constraints.empty();
  int row = 0;
  for (size_t j = 0; j < constraints.size(); ++j) {
    const Constraint& c = *constraints[j];
    const int m = c.dimension();
    Block& b = blocks_[j];  // evaluated in place: no copy of the rows
    b.C.resize(m);
    b.ja.resize(m, 6);
    b.jb.resize(m, 6);
    b.bias.resize(m);
    b.point = false;
    b.bias_wanted = with_bias;
    c.evaluate(bodyOf(c.bodyA()), bodyOf(c.bodyB()), b);
    b.point = b.point && m == 3;
    b.body_a = c.bodyA();
    b.body_b = c.bodyB();
    b.row = row;
    b.rows = m;
    b.constraint = &c;
    row += m;
  }
  // The stacked C and J'q' in a second pass: a joint writes its rows entry by entry, and copying
  // them right after its evaluate() read those stores back 16 bytes at a time (failed store
  // forwarding, half of this function's samples at N = 8). By now they have left the store buffer.
  // Three rows (a point joint) by fixed-size copies: a runtime-size copy of three entries ran
  // Eigen's alignment peeling, a loop and its tail each time.
  for (const Block& b : blocks_) {
    if (b.rows == 3) {
      c_.segment<3>(b.row) = b.C.head<3>();
      bias_.segment<3>(b.row) = b.bias.head<3>();
    } else {
      c_.segment(b.row, b.rows) = b.C;
      bias_.segment(b.row, b.rows) = b.bias;
    }
  }
}

double ConstraintSystem::maxError() const {
  if (!max_error_known_) {
    max_error_ = 0.0;
    for (const Block& b : blocks_) max_error_ = std::max(max_error_, b.constraint->error(b));
    max_error_known_ = true;
  }
  return max_error_;
}

Eigen::VectorXd ConstraintSystem::times(const std::vector<Vector6d>& per_body) const {
  Eigen::VectorXd out;
  timesInto(per_body, out);
  return out;
}

namespace {
// A block's Jacobian seen as a fixed 3 x 6 (spherical joints, the common case): fixed-size
// products instead of loops over a runtime row count.
using Jacobian3 = Eigen::Matrix<double, 3, 6>;
Eigen::Map<const Jacobian3> fixed3(const JacobianBlock& j) { return Eigen::Map<const Jacobian3>(j.data()); }
}  // namespace

void ConstraintSystem::timesInto(const std::vector<Vector6d>& per_body, Eigen::VectorXd& out) const {
  out.setZero(rows_);
  for (const Block& b : blocks_) {
    if (b.point) {  // J_a x_a + J_b x_b = (v_a + w_a x arm_a) - (v_b + w_b x arm_b)
      Eigen::Vector3d s = Eigen::Vector3d::Zero();
      if (b.body_a != kWorldBody) {
        const Vector6d& x = per_body[b.body_a];
        s += x.head<3>() + x.tail<3>().cross(b.arm_a);
      }
      if (b.body_b != kWorldBody) {
        const Vector6d& x = per_body[b.body_b];
        s -= x.head<3>() + x.tail<3>().cross(b.arm_b);
      }
      out.segment<3>(b.row) = s;
      continue;
    }
    if (b.rows == 3) {
      if (b.body_a != kWorldBody) out.segment<3>(b.row) += fixed3(b.ja) * per_body[b.body_a];
      if (b.body_b != kWorldBody) out.segment<3>(b.row) += fixed3(b.jb) * per_body[b.body_b];
      continue;
    }
    if (b.body_a != kWorldBody) out.segment(b.row, b.rows) += b.ja * per_body[b.body_a];
    if (b.body_b != kWorldBody) out.segment(b.row, b.rows) += b.jb * per_body[b.body_b];
  }
}

void ConstraintSystem::timesInto(const std::vector<Vector6d>& per_body, const std::vector<RigidBody>& bodies,
                                 Eigen::VectorXd& out, Eigen::VectorXd& out_velocity) const {
  out.setZero(rows_);
  out_velocity.setZero(rows_);
  const auto velocity = [&](int i) {
    Vector6d v;
    v << bodies[i].v, bodies[i].w;
    return v;
  };
  for (const Block& b : blocks_) {
    if (b.point) {  // as timesInto above, for x and for (v; w)
      Eigen::Vector3d s = Eigen::Vector3d::Zero(), sv = Eigen::Vector3d::Zero();
      if (b.body_a != kWorldBody) {
        const Vector6d& x = per_body[b.body_a];
        const RigidBody& body = bodies[b.body_a];
        s += x.head<3>() + x.tail<3>().cross(b.arm_a);
        sv += body.v + body.w.cross(b.arm_a);
      }
      if (b.body_b != kWorldBody) {
        const Vector6d& x = per_body[b.body_b];
        const RigidBody& body = bodies[b.body_b];
        s -= x.head<3>() + x.tail<3>().cross(b.arm_b);
        sv -= body.v + body.w.cross(b.arm_b);
      }
      out.segment<3>(b.row) = s;
      out_velocity.segment<3>(b.row) = sv;
      continue;
    }
    if (b.rows == 3) {
      if (b.body_a != kWorldBody) {
        out.segment<3>(b.row) += fixed3(b.ja) * per_body[b.body_a];
        out_velocity.segment<3>(b.row) += fixed3(b.ja) * velocity(b.body_a);
      }
      if (b.body_b != kWorldBody) {
        out.segment<3>(b.row) += fixed3(b.jb) * per_body[b.body_b];
        out_velocity.segment<3>(b.row) += fixed3(b.jb) * velocity(b.body_b);
      }
      continue;
    }
    if (b.body_a != kWorldBody) {
      out.segment(b.row, b.rows) += b.ja * per_body[b.body_a];
      out_velocity.segment(b.row, b.rows) += b.ja * velocity(b.body_a);
    }
    if (b.body_b != kWorldBody) {
      out.segment(b.row, b.rows) += b.jb * per_body[b.body_b];
      out_velocity.segment(b.row, b.rows) += b.jb * velocity(b.body_b);
    }
  }
}

void ConstraintSystem::addTransposeTimes(const Eigen::VectorXd& lambda, const std::vector<RigidBody>& bodies,
                                         std::vector<Vector6d>& out) const {
  for (const Block& b : blocks_) {
    if (b.point) {  // J_a^T lambda = [lambda; arm_a x lambda], J_b^T lambda = -[lambda; arm_b x lambda]
      const Eigen::Vector3d l = lambda.segment<3>(b.row);
      if (b.body_a != kWorldBody && bodies[b.body_a].isDynamic()) {
        out[b.body_a].head<3>() += l;
        out[b.body_a].tail<3>() += b.arm_a.cross(l);
      }
      if (b.body_b != kWorldBody && bodies[b.body_b].isDynamic()) {
        out[b.body_b].head<3>() -= l;
        out[b.body_b].tail<3>() -= b.arm_b.cross(l);
      }
      continue;
    }
    if (b.rows == 3) {
      const auto l = lambda.segment<3>(b.row);
      if (b.body_a != kWorldBody && bodies[b.body_a].isDynamic()) out[b.body_a] += fixed3(b.ja).transpose() * l;
      if (b.body_b != kWorldBody && bodies[b.body_b].isDynamic()) out[b.body_b] += fixed3(b.jb).transpose() * l;
      continue;
    }
    const auto l = lambda.segment(b.row, b.rows);
    if (b.body_a != kWorldBody && bodies[b.body_a].isDynamic()) out[b.body_a] += b.ja.transpose() * l;
    if (b.body_b != kWorldBody && bodies[b.body_b].isDynamic()) out[b.body_b] += b.jb.transpose() * l;
  }
}

}  // namespace ponyhop

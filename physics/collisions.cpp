#include "physics/collisions.h"

#include <algorithm>
#include <cmath>

#include "physics/mesh_sdf.h"
#include "physics/pgs.h"
#include "physics/solver_factory.h"
#include "physics/stabilization.h"
#include "physics/world.h"

namespace ponyhop {

namespace {

constexpr double kActiveSlop = 1e-6;  // m: a contact this close after the stage persists
constexpr int kPositionPasses = 4;    // push-out and joint re-projection rounds at most
// m: a search against a grid that finds nothing within reach goes on until it bounds the link's
// gap this far beyond reach (where the grid's spacing allows), so the next substeps can skip the
// link while it has moved less than that (Collisions::detect).
constexpr double kClearanceSlack = 1e-3;
// m: an overlap this small is left. Between analytic shapes 1 um (a push-out to the last 1e-10 m
// only repeats searches). Against a grid (accurate to about 0.1 mm) 10 um, a tenth of the impact
// tolerance: a link resting on the head sinks a few um a substep, and pushing each of those out
// took a second search of every link, most of the stage.
double overlapTolerance(const std::vector<Collisions::Row>& rows) {
  for (const Collisions::Row& r : rows)
    if (r.grid) return 1e-5;
  return kActiveSlop;
}
// The solves stop at the accuracy of the geometry. Against a grid: 1e-4 of the impulse (or
// push-out) scale, at most 200 sweeps (its normals are good to a few 1e-2, its gaps to 0.1 mm).
// Analytic shapes only: 1e-13, at most 5000 (exact normals: a box rests without creeping).
PgsSettings pgsSettings(const std::vector<Collisions::Row>& rows, bool warm_start) {
  for (const Collisions::Row& r : rows)
    if (r.grid) return {1e-4, 200, warm_start, true};
  return {1e-13, 5000, warm_start, true};
}

// The dynamic bodies' kinetic energy, 1/2 m v^2 + 1/2 w_b . (I w_b) with w_b = R^T w the angular
// velocity in the body's frame, where the inertia is diagonal: RigidBody::kineticEnergy's value
// without building R I R^T (two 3 x 3 products a body). The impulses' energy readout.
double kineticEnergyOf(const std::vector<RigidBody>& bodies) {
  double e = 0.0;
  for (const RigidBody& b : bodies) {
    if (!b.isDynamic()) continue;
    const Eigen::Vector3d wb = renormalized(b.q).conjugate() * b.w;
    e += 0.5 * b.mass * b.v.squaredNorm() + 0.5 * wb.dot(b.inertia.cwiseProduct(wb));
  }
  return e;
}

// Whether a point (in the grid's frame) lies in the grid's box, where its Lipschitz bound holds.
bool inGrid(const SignedDistanceGrid& g, const Eigen::Vector3d& p) {
  return (p.array() >= g.origin().array()).all() && (p.array() <= g.upper().array()).all();
}

Vector6d velocityOf(const RigidBody& b) {
  Vector6d v;
  v << b.v, b.w;
  return v;
}

}  // namespace

Collisions::Collisions(const CollisionParams& params, SolverKind solver)
    : params_(params), solver_(makeConstraintSolver(solver)), kind_(solver) {}

int Collisions::addShape(int body, Shape shape) {
  shapes_.push_back(std::move(shape));
  owners_.push_back(body);
  return static_cast<int>(shapes_.size()) - 1;
}

void Collisions::addPair(int shape_a, int shape_b, double friction, double restitution) {
  pairs_.push_back({shape_a, shape_b, friction, restitution});
  grid_only_ = std::all_of(pairs_.begin(), pairs_.end(), [this](const Pair& p) {
    return shapes_[p.a].type == ShapeType::Sdf || shapes_[p.b].type == ShapeType::Sdf;
  });
}

void Collisions::addConeLimit(int parent, const Eigen::Vector3d& parent_axis, int child,
                              const Eigen::Vector3d& child_axis, double max_angle) {
  limits_.push_back({false, parent, child, parent_axis.normalized(), child_axis.normalized(),
                     Eigen::Quaterniond::Identity(), max_angle});
}

void Collisions::addTwistLimit(int parent, int child, const Eigen::Vector3d& child_axis, double max_angle,
                               const std::vector<RigidBody>& bodies) {
  const Eigen::Quaterniond rest = bodyOf(bodies, parent).q.conjugate() * bodyOf(bodies, child).q;
  limits_.push_back(
      {true, parent, child, Eigen::Vector3d::Zero(), child_axis.normalized(), rest.normalized(), max_angle});
}

void Collisions::attach(World& world) {
  world.addContactSet(shared_from_this());
  coresInGrids(world.bodies(), memory_.cores);  // the first substep's moves count from here
}

void Collisions::update(World& world) {
  if (!world.ok()) return;
  reduced_ = world.reduced();  // featherstone: the responses in joint space
  if (reduced_ && reduced_->loopRows() > 0) {
    reduced_ = nullptr;
    return world.fail(
        "collisions: physics.solver = featherstone takes contacts on a tree only (its contact impulses do not "
        "keep closed loops); use solver = tree or dense for this scene");
  }
  // The same kind of solver factors the same matrix to the same bits: the World's factorization
  // serves the impulses' build when it was made at this state (docs/PHYSICS.md, "Collisions").
  world_factored_ = !reduced_ && world.params().solver == kind_ ? world.solverFactoredAt(world.bodies()) : nullptr;
  const Status s = resolve(world.bodies(), world.joints());
  reduced_ = nullptr;
  world_factored_ = nullptr;
  if (!s.ok()) world.fail("collisions: " + s.message());
}

bool Collisions::impactInside(const World& world) const { return impactIn(world.bodies()); }

void Collisions::restoreState(const std::any& state) {
  if (const auto* m = std::any_cast<Memory>(&state)) memory_ = *m;
  at_.too_far = -1;  // measured against the memory just replaced
}

std::vector<Collisions::Row> Collisions::detect(const std::vector<RigidBody>& bodies, double reach,
                                                long* queries) const {
  std::vector<Row> rows;
  std::vector<ContactPoint> points;
  const double collide_reach = reach + params_.margin;
  clearances_.resize(pairs_.size());
  const std::vector<Eigen::Vector3d>* cores = nullptr;  // asked for once, at the first grid pair
  size_t core = 0;       // the pair's core ends in coresAt(): two per pair of a rounded shape and a grid
  int grid_placed = -1;  // the grid shape placed in grid_placement (-1: none yet)
  PlacedShape grid_placement;
  for (size_t k = 0; k < pairs_.size(); ++k) {
    const Pair& pr = pairs_[k];
    int ri = 0, gi = 0;
    const bool grid_pair = roundedAndGrid(pr, ri, gi);
    const size_t ends_at = core;
    if (grid_pair) core += 2;
    const int ba = owners_[pr.a], bb = owners_[pr.b];
    if (!dynamicBody(bodies, ba) && !dynamicBody(bodies, bb)) continue;
    const RigidBody& A = bodyOf(bodies, ba);
    const RigidBody& B = bodyOf(bodies, bb);
    points.clear();
    GridClearance clearance;
    const Eigen::Vector3d* ends = nullptr;
    const SignedDistanceGrid* grid = grid_pair ? shapes_[gi].sdf.get() : nullptr;
    if (grid) {
      const SignedDistanceGrid& g = *grid;
      if (!cores) cores = &coresAt(bodies);
      ends = &(*cores)[ends_at];
      const Clearance& last = clearances_[k];
      // Inside the grid's box (convex: the segments between old and new points stay in it) the
      // interpolant changes by at most lip |dx|_1, and each core point moves by an affine mix of
      // its ends' moves, so by at most the larger one's |.|_1. 1e-9 m covers the round-off of the
      // two ways the ends are computed.
      if (last.valid && inGrid(g, ends[0]) && inGrid(g, ends[1])) {
        const double moved = std::max((ends[0] - last.a).lpNorm<1>(), (ends[1] - last.b).lpNorm<1>());
        if (last.lower - g.lipschitz() * moved - 1e-9 >= collide_reach) continue;
      }
      clearance.certify = collide_reach + kClearanceSlack;
    }
    // The grid's placement is the same for every pair of its (the ponytail's 9): made once.
    const auto placed = [&](int shape, const RigidBody& body) {
      if (shapes_[shape].type != ShapeType::Sdf) return place(shapes_[shape], body.x, body.q);
      if (shape != grid_placed) {
        grid_placement = place(shapes_[shape], body.x, body.q);
        grid_placed = shape;
      }
      return grid_placement;
    };
    collide(placed(pr.a, A), placed(pr.b, B), collide_reach, points, queries, grid ? &clearance : nullptr);
    if (grid) {
      Clearance& last = clearances_[k];
      last.valid =
          points.empty() && clearance.lower > collide_reach && inGrid(*grid, ends[0]) && inGrid(*grid, ends[1]);
      last.lower = clearance.lower;
      last.a = ends[0];
      last.b = ends[1];
    }
    for (size_t i = 0; i < points.size(); ++i) {
      Row r;
      r.a = ba;
      r.b = bb;
      r.point = points[i].point;
      r.normal = points[i].normal;
      r.gap = points[i].gap - params_.margin;
      r.mu = pr.mu >= 0.0 ? pr.mu : params_.friction;
      r.e = pr.e >= 0.0 ? pr.e : params_.restitution;
      r.key0 = static_cast<int>(k);
      r.key1 = static_cast<int>(i);
      r.grid = shapes_[pr.a].type == ShapeType::Sdf || shapes_[pr.b].type == ShapeType::Sdf;
      r.feature = points[i].feature;
      rows.push_back(r);
    }
  }
  for (size_t k = 0; k < limits_.size(); ++k) {
    Row r;
    if (limitRow(bodies, k, reach, r)) rows.push_back(r);
  }
  return rows;
}

bool Collisions::limitRow(const std::vector<RigidBody>& bodies, size_t k, double reach, Row& r) const {
  const Limit& l = limits_[k];
  const RigidBody& P = bodyOf(bodies, l.parent);
  const RigidBody& C = bodyOf(bodies, l.child);
  const Eigen::Vector3d zc = C.q * l.child_axis;
  r.a = l.child;
  r.b = l.parent;
  r.angular = true;
  r.key0 = -1 - static_cast<int>(k);
  if (!l.twist) {
    const Eigen::Vector3d zp = P.q * l.parent_axis;
    const Eigen::Vector3d k_axis = zp.cross(zc);
    const double theta = std::atan2(k_axis.norm(), zp.dot(zc));
    r.gap = l.max_angle - theta;
    if (!(r.gap < reach) || k_axis.norm() < 1e-12) return false;
    r.normal = -k_axis.normalized();
  } else {
    const Eigen::Quaterniond dev = (P.q * l.rest).conjugate() * C.q;
    const double along = dev.vec().dot(l.child_axis);
    double tau = 2.0 * std::atan2(along, dev.w());
    if (tau > M_PI) tau -= 2.0 * M_PI;
    if (tau < -M_PI) tau += 2.0 * M_PI;
    r.gap = l.max_angle - std::abs(tau);
    if (!(r.gap < reach)) return false;
    r.normal = (tau > 0.0 ? -1.0 : 1.0) * zc;
  }
  return true;
}

Collisions::AtState& Collisions::at(const std::vector<RigidBody>& bodies) const {
  bool same = at_valid_ && at_.x.size() == bodies.size() && at_.margin == params_.margin;
  for (size_t i = 0; same && i < bodies.size(); ++i)
    same = at_.x[i] == bodies[i].x && at_.q[i].coeffs() == bodies[i].q.coeffs();
  if (same) return at_;
  at_.x.resize(bodies.size());
  at_.q.resize(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) {
    at_.x[i] = bodies[i].x;
    at_.q[i] = bodies[i].q;
  }
  at_.margin = params_.margin;
  at_.searched = at_.cored = false;
  at_.too_far = -1;
  at_valid_ = true;
  return at_;
}

const std::vector<Collisions::Row>& Collisions::touching(const std::vector<RigidBody>& bodies) const {
  AtState& s = at(bodies);
  if (!s.searched) {
    s.rows = detect(bodies, kActiveSlop, &stats_.queries);
    s.searched = true;
  }
  return s.rows;
}

const std::vector<Eigen::Vector3d>& Collisions::coresAt(const std::vector<RigidBody>& bodies) const {
  AtState& s = at(bodies);
  if (!s.cored) {
    coresInGrids(bodies, s.cores);
    s.cored = true;
  }
  return s.cores;
}

std::vector<Collisions::Row> Collisions::remeasure(const std::vector<RigidBody>& bodies,
                                                   const std::vector<Row>& found) const {
  std::vector<Row> rows;
  for (const Row& f : found) {
    if (f.angular) continue;  // the limits: all of them below
    const Pair& pr = pairs_[f.key0];
    const RigidBody& A = bodyOf(bodies, owners_[pr.a]);
    const RigidBody& B = bodyOf(bodies, owners_[pr.b]);
    const ContactPoint cp =
        measureAt(place(shapes_[pr.a], A.x, A.q), place(shapes_[pr.b], B.x, B.q), f.feature, &stats_.queries);
    if (!(cp.gap - params_.margin < kActiveSlop)) continue;
    Row r = f;
    r.point = cp.point;
    r.normal = cp.normal;
    r.gap = cp.gap - params_.margin;
    rows.push_back(r);
  }
  for (size_t k = 0; k < limits_.size(); ++k) {
    Row r;
    if (limitRow(bodies, k, kActiveSlop, r)) rows.push_back(r);
  }
  return rows;
}

bool Collisions::impactIn(const std::vector<RigidBody>& bodies) const {
  for (const Row& r : touching(bodies)) {
    if (r.gap < -params_.impact_tolerance && !memory_.active.count({r.key0, r.key1})) return true;
  }
  return movedTooFar(bodies);
}

bool Collisions::roundedAndGrid(const Pair& pair, int& ri, int& gi) const {
  ri = pair.a;
  gi = pair.b;
  if (shapes_[ri].type == ShapeType::Sdf) std::swap(ri, gi);
  return shapes_[gi].type == ShapeType::Sdf && shapes_[ri].rounded();
}

void Collisions::coresInGrids(const std::vector<RigidBody>& bodies, std::vector<Eigen::Vector3d>& cores) const {
  cores.clear();
  // World to a grid's frame (the inverse of its body's pose times its local pose) as a matrix and
  // an origin, made once for the pairs that share the grid (every pair of the ponytail: one head);
  // each core end is then two matrix products (quaternion rotations cost about twice as much,
  // and this runs twice per substep).
  int grid = -1;
  Eigen::Matrix3d to_grid = Eigen::Matrix3d::Identity();
  Eigen::Vector3d grid_origin = Eigen::Vector3d::Zero();
  for (const Pair& pr : pairs_) {
    int ri = 0, gi = 0;
    if (!roundedAndGrid(pr, ri, gi)) continue;
    if (gi != grid) {
      const Shape& g = shapes_[gi];
      const RigidBody& G = bodyOf(bodies, owners_[gi]);
      to_grid = (G.q * g.rotation).conjugate().toRotationMatrix();
      grid_origin = G.x + G.q * g.offset;
      grid = gi;
    }
    const Shape& r = shapes_[ri];
    const RigidBody& R = bodyOf(bodies, owners_[ri]);
    const Eigen::Matrix3d body = R.q.toRotationMatrix();
    // The core's ends in its body's frame: the shape's offset -+ half its length along its z.
    const Eigen::Vector3d axis =
        (r.type == ShapeType::Capsule ? r.half_length : 0.0) * (r.rotation * Eigen::Vector3d::UnitZ());
    for (const Eigen::Vector3d& local : {Eigen::Vector3d(r.offset + axis), Eigen::Vector3d(r.offset - axis)})
      cores.push_back(to_grid * (R.x + body * local - grid_origin));
  }
}

// Why this bounds what passes between two stages: docs/PHYSICS.md, "No pass-through". Every core
// point moves (in the grid's frame) by an affine mix of its ends' displacements, so by at most the
// larger; the true distance is 1-Lipschitz, so a core whose points all move less than their
// clearance plus half the thinnest radius never reaches the surface.
// Asked once per state (the impact check's and the stage's question are the same one).
bool Collisions::movedTooFar(const std::vector<RigidBody>& bodies) const {
  AtState& s = at(bodies);
  if (s.too_far >= 0) return s.too_far == 1;
  const std::vector<Eigen::Vector3d>& cores = coresAt(bodies);
  size_t k = 0;
  s.too_far = 0;
  for (const Pair& pr : pairs_) {
    int ri = 0, gi = 0;
    if (!roundedAndGrid(pr, ri, gi)) continue;
    const Shape* r = &shapes_[ri];
    const Shape* g = &shapes_[gi];
    if (k + 2 > memory_.cores.size()) break;  // no stage yet: nothing to compare with
    const Eigen::Vector3d& a0 = memory_.cores[k];
    const Eigen::Vector3d& b0 = memory_.cores[k + 1];
    const double moved = std::max((cores[k] - a0).norm(), (cores[k + 1] - b0).norm());
    k += 2;
    const double ra = r->type == ShapeType::Capsule ? r->radius_a : r->radius;
    const double rb = r->type == ShapeType::Capsule ? r->radius_b : r->radius;
    const double allowed = 0.5 * std::min(ra, rb);
    if (moved <= allowed) continue;  // the common case: no query
    // The clearance at the last stage, from the grid at the core's ends there (the grid does not
    // move in its own frame); the margin is skin, not clearance.
    const double clearance = gridGapBound(*g->sdf, a0, b0, ra, rb) - params_.margin;
    if (moved > allowed + std::max(0.0, clearance)) {
      s.too_far = 1;
      break;
    }
  }
  return s.too_far == 1;
}

void Collisions::buildJacobians(const std::vector<RigidBody>& bodies, const std::vector<Row>& rows, bool normals_only) {
  jrows_.clear();
  for (size_t c = 0; c < rows.size(); ++c) {
    const Row& r = rows[c];
    Eigen::Vector3d dirs[3] = {r.normal, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    int count = 1;
    if (!normals_only && !r.angular && r.mu > 0.0) {
      dirs[1] = r.normal.unitOrthogonal();
      dirs[2] = r.normal.cross(dirs[1]);
      count = 3;
    }
    for (int k = 0; k < count; ++k) {
      JRow j{r.a, r.b, static_cast<int>(c), Vector6d::Zero(), Vector6d::Zero()};
      if (r.angular) {
        j.ja << Eigen::Vector3d::Zero(), dirs[k];
        j.jb << Eigen::Vector3d::Zero(), -dirs[k];
      } else {
        j.ja << dirs[k], (r.point - bodyOf(bodies, r.a).x).cross(dirs[k]);
        j.jb << -dirs[k], -(r.point - bodyOf(bodies, r.b).x).cross(dirs[k]);
      }
      jrows_.push_back(j);
    }
  }
}

// W_c columns through the joints' Schur complement, and D = J_c W_c.
bool Collisions::buildDelassus(const std::vector<RigidBody>& bodies, const Constraints& joints,
                               const ConstraintSolver* factored) {
  const size_t n = bodies.size();
  const int m = static_cast<int>(jrows_.size());
  if (reduced_) {
    // Reduced coordinates: W_c = Phi H^-1 Phi^T J_c^T, the joints hold by construction.
    reduced_rows_.resize(m);
    for (int k = 0; k < m; ++k) reduced_rows_[k] = {jrows_[k].a, jrows_[k].b, jrows_[k].ja, jrows_[k].jb};
    if (!reduced_->impulseResponse(bodies, reduced_rows_, w_)) return false;
  }
  if (!reduced_) joint_system_.evaluate(bodies, joints);
  const bool has_joints = !reduced_ && joint_system_.rows() > 0;
  if (has_joints && !factored && !solver_->factor(bodies, joint_system_)) return false;
  const ConstraintSolver& joint_solver = factored ? *factored : *solver_;
  // The columns' storage and the joint solves' work space are kept from stage to stage: a
  // steady stage allocates nothing here. w_ never shrinks (the push-out keeps its first rows):
  // a column beyond the rows in use keeps its storage for the next stage's.
  if (w_.size() < static_cast<size_t>(m)) w_.resize(m);
  // M^-1 of every column's impulse and joint correction (applyInverseMass and the solver's
  // massWeightedTransposeInto, written out) with each body's R I^-1 R^T made once per build rather
  // than once per body and column: the same products, so the same values.
  if (!reduced_) {
    inverse_inertia_.resize(n);
    for (size_t i = 0; i < n; ++i)
      if (bodies[i].isDynamic()) inverse_inertia_[i] = bodies[i].worldInverseInertia();
  }
  const auto inverse_mass = [&](size_t i, const Vector6d& x) {
    return applyInverseMass(bodies[i], inverse_inertia_[i], x);
  };
  for (int k = 0; k < m && !reduced_; ++k) {
    const JRow& j = jrows_[k];
    std::vector<Vector6d>& w = w_[k];
    w.assign(n, Vector6d::Zero());
    if (dynamicBody(bodies, j.a)) w[j.a] += inverse_mass(j.a, j.ja);
    if (dynamicBody(bodies, j.b)) w[j.b] += inverse_mass(j.b, j.jb);
    if (has_joints) {
      joint_system_.timesInto(w, joint_rhs_);
      joint_solver.solveInto(joint_rhs_, joint_y_);
      joint_corr_.assign(n, Vector6d::Zero());
      joint_system_.addTransposeTimes(joint_y_, bodies, joint_corr_);
      // A kinematic body (the keyframed head) does not move: addTransposeTimes gives it no
      // reaction, so its entry stays the zero the column started with.
      for (size_t i = 0; i < n; ++i)
        if (bodies[i].isDynamic()) w[i] -= inverse_mass(i, joint_corr_[i]);
    }
  }
  // D_ik = J_i W_k, symmetrized against the round-off (D is symmetric positive semidefinite):
  // both entries of a pair get the mean of the two products, in place.
  const auto entry = [this](int i, int k) {
    const JRow& j = jrows_[i];
    double v = 0.0;
    if (j.a != kWorldBody) v += j.ja.dot(w_[k][j.a]);
    if (j.b != kWorldBody) v += j.jb.dot(w_[k][j.b]);
    return v;
  };
  delassus_.resize(m, m);
  for (int i = 0; i < m; ++i) {
    delassus_(i, i) = entry(i, i);
    for (int k = i + 1; k < m; ++k) delassus_(i, k) = delassus_(k, i) = 0.5 * (entry(i, k) + entry(k, i));
  }
  return true;
}

Status Collisions::resolve(std::vector<RigidBody>& bodies, const Constraints& joints) {
  stats_.active = 0;
  stats_.deepest = 0.0;
  stats_.overshoot = 0.0;
  stats_.iterations = 0;
  // The World splits a substep in which a link moved too far (impactIn) until its splits run out:
  // one accepted anyway is counted.
  if (movedTooFar(bodies)) ++stats_.too_fast;
  // The rows found at the active set's reach, and of them those that overlap (gap < 0).
  std::vector<Row> found = touching(bodies), rows;
  const auto overlapping = [&rows, &found] {
    rows.clear();
    for (const Row& r : found)
      if (r.gap < 0.0) rows.push_back(r);
  };
  const auto finish = [&] {
    memory_.cores = coresAt(bodies);
    at_.too_far = -1;  // measured against the cores just replaced
    memory_.active.clear();
    for (const Row& r : found) memory_.active.insert({r.key0, r.key1});
    stats_.active = static_cast<int>(memory_.active.size());
    return Status{};
  };
  overlapping();
  if (rows.empty()) {
    memory_.impulses.clear();
    return finish();
  }
  bool impact = false;
  for (const Row& r : rows) {
    // Contacts' gaps are lengths, limits' angles: each has its own readout.
    double& worst = r.angular ? stats_.overshoot : stats_.deepest;
    worst = std::max(worst, -r.gap);
    if (!memory_.active.count({r.key0, r.key1})) impact = true;
  }
  if (impact) ++stats_.impacts;

  // 1. Impulses.
  buildJacobians(bodies, rows, false);
  if (!buildDelassus(bodies, joints, world_factored_)) return Status::error(singularMessage());
  const int m = static_cast<int>(jrows_.size());
  Eigen::VectorXd u0(m), target = Eigen::VectorXd::Zero(m), p = Eigen::VectorXd::Zero(m);
  std::vector<std::pair<int, int>> blocks;
  std::vector<double> mu;
  for (int i = 0; i < m; ++i) {
    const JRow& j = jrows_[i];
    u0(i) = j.ja.dot(velocityOf(bodyOf(bodies, j.a))) + j.jb.dot(velocityOf(bodyOf(bodies, j.b)));
    if (i == 0 || jrows_[i - 1].block != j.block) {
      const Row& r = rows[j.block];
      const int count = (i + 1 < m && jrows_[i + 1].block == j.block) ? 3 : 1;
      blocks.push_back({i, count});
      mu.push_back(r.mu);
      if (u0(i) < 0.0) target(i) = -r.e * u0(i);  // restitution of the approach speed
      // The warm start: this contact's impulses at the last stage (its tangent frame is the same
      // function of the normal, which moved little).
      for (const auto& [key, last] : memory_.impulses)
        if (key == std::make_pair(r.key0, r.key1)) p.segment(i, count) = last.head(count);
    }
  }
  const double energy_before = kineticEnergyOf(bodies);
  const PgsResult solved = projectedGaussSeidel(delassus_, u0, target, blocks, mu, p, pgsSettings(rows, true));
  stats_.iterations = solved.sweeps;
  stats_.sweeps += solved.sweeps;
  stats_.capped += solved.capped ? 1 : 0;
  memory_.impulses.clear();
  for (const auto& [first, count] : blocks) {
    Eigen::Vector3d last = Eigen::Vector3d::Zero();
    last.head(count) = p.segment(first, count);
    const Row& r = rows[jrows_[first].block];
    memory_.impulses.push_back({{r.key0, r.key1}, last});
  }
  for (int k = 0; k < m; ++k) {
    if (p(k) == 0.0) continue;
    for (size_t i = 0; i < bodies.size(); ++i) {
      if (!bodies[i].isDynamic()) continue;
      bodies[i].v += p(k) * w_[k][i].head<3>();
      bodies[i].w += p(k) * w_[k][i].tail<3>();
    }
  }
  stats_.max_energy_gain = std::max(stats_.max_energy_gain, kineticEnergyOf(bodies) - energy_before);

  // 2. Positions: push out what overlaps, keep the joints. The impulses moved no body: the first
  // pass's rows are the impulses' own.
  for (int pass = 0; pass < kPositionPasses; ++pass) {
    if (pass > 0) overlapping();
    double worst = 0.0;
    for (const Row& r : rows) worst = std::max(worst, -r.gap);
    if (worst <= overlapTolerance(rows)) break;
    const int mo = static_cast<int>(rows.size());
    if (pass == 0) {
      // The same poses and rows as the impulses: their W_c columns and D, normal rows only (each
      // block's first), without factoring the joints again. Block i's first row is at i or after
      // it, so the columns are gathered in place by swaps (no column is reallocated) and D's
      // entries into a kept matrix.
      normal_d_.resize(mo, mo);
      for (int i = 0; i < mo; ++i) {
        for (int k = 0; k < mo; ++k) normal_d_(i, k) = delassus_(blocks[i].first, blocks[k].first);
        std::swap(w_[i], w_[blocks[i].first]);
      }
      delassus_.swap(normal_d_);
    } else {
      buildJacobians(bodies, rows, true);
      if (!buildDelassus(bodies, joints)) return Status::error(singularMessage());
    }
    Eigen::VectorXd gap(mo);
    std::vector<std::pair<int, int>> nb;
    std::vector<double> zero(mo, 0.0);
    for (int i = 0; i < mo; ++i) {
      gap(i) = rows[i].gap;
      nb.push_back({i, 1});
    }
    Eigen::VectorXd d;
    const PgsResult pushed =
        projectedGaussSeidel(delassus_, gap, Eigen::VectorXd::Zero(mo), nb, zero, d, pgsSettings(rows, false));
    stats_.iterations += pushed.sweeps;
    stats_.sweeps += pushed.sweeps;
    stats_.capped += pushed.capped ? 1 : 0;
    std::vector<Vector6d>& dq = joint_corr_;  // free between the Delassus builds
    dq.assign(bodies.size(), Vector6d::Zero());
    for (int k = 0; k < mo; ++k)
      for (size_t i = 0; i < bodies.size(); ++i) dq[i] += d(k) * w_[k][i];
    for (size_t i = 0; i < bodies.size(); ++i) {
      RigidBody& b = bodies[i];
      if (!b.isDynamic()) continue;
      b.x += dq[i].head<3>();
      b.q = (quaternionFromRotationVector(dq[i].tail<3>()) * b.q).normalized();
    }
    if (reduced_) {
      reduced_->projectBodies(bodies);  // back onto the joints: coordinates read, bodies written
    } else if (!joints.empty()) {
      const ProjectionResult pr = projectPositions(bodies, joints, joint_system_, *solver_);
      if (!pr.status.ok()) return Status::error("joint projection after the push-out: " + pr.status.message());
    }
    // The next pass's check and, after the last, the active set. Against grids the rows found
    // are measured again where they were (a push-out moves a link by about its overlap, a few um;
    // the deepest point moves along it by as little, and the gap there is second order in that):
    // a second search of every link was most of a touching stage. A link it brings within reach
    // is found by the next substep's search. Analytic shapes are searched again (exact contacts:
    // a box's corners change as it settles).
    found = grid_only_ ? remeasure(bodies, found) : touching(bodies);
  }

  // 3. The active set: the contacts within reach after the last push-out.
  return finish();
}

}  // namespace ponyhop

// Contacts and joint limits as unilateral rows, solved together with the joints (docs/PHYSICS.md,
// "Collisions").
//
// Sources of rows. Shapes (physics/shapes.h) are attached to bodies (or to the world: static
// scenery); pairs of shapes are named explicitly (a scene models only the collisions it names).
// Each pair yields contact points (normal n from b to a, gap phi); each point gives a normal row
// and, with friction, two tangent rows. Joint limits (ConeLimit: the swing between two bodies'
// axes, TwistLimit: the turn about the child's axis) give one angular row each when active.
//
// The contact stage, after every accepted substep (World's contact hook):
//   1. Impulses. The rows' Jacobian J_c acts on the velocities that satisfy the joints (J_j v = 0
//      after the step). The joints stay equality rows: an impulse P on the contact rows moves the
//      velocities by dv = W_c P with  W_c = M^-1 J_c^T - M^-1 J_j^T A_jj^-1 J_j M^-1 J_c^T,
//      A_jj = J_j M^-1 J_j^T factored by the World's own solver (dense or tree): each column is
//      one joint solve. The contact-space Delassus matrix D = J_c W_c is the Schur complement of
//      the joint rows. Then a mixed complementarity problem in P:
//        normal    P_n >= 0,  v_n' = v_n + (D P)_n >= -e v_n^-,  P_n (v_n' + e v_n^-) = 0
//        friction  |P_t| <= mu P_n (a cone: an isotropic disc per contact), P_t opposite to v_t'
//                  when sliding, v_t' = 0 when sticking (maximal dissipation)
//      solved by projected Gauss-Seidel with a disc projection for the tangents, warm-started from
//      the last stage's impulses of the same contacts, and stopped at the geometry's accuracy:
//      with a distance grid in the solve at 1e-4 of the impulse scale (the grid's normals are no
//      better than a few 1e-2) and 200 sweeps at most, with analytic shapes only at 1e-13 and
//      5000 (a stop at the cap is counted: CollisionStats::capped). With e = 0 the kinetic energy cannot rise:
//      dK = P.v' - P^T D P / 2 <= 0, since P_n v_n' = 0 and P_t.v_t' <= 0.
//   2. Positions. What still overlaps by more than 1 um (10 um against a grid) is pushed out by
//      the least mass-weighted displacement that keeps the joints (the same W_c with the gaps as
//      targets, normal rows only), then the joints are projected back onto C = 0 (their
//      second-order error).
//   3. The active set: contacts that are touching after the stage are "active"; the next step
//      treats them as persisting.
// Contacts are found once per state: every search runs at the active set's reach (1 um) and the
// rows are kept with the poses they were found at, so the impact check, the impulses and the
// first push-out pass share one search (and movedTooFar() is asked once per state). After a
// push-out against grids the rows found are measured again where they were, without a search
// (remeasure()): the next pass's check and, after the last, the active set. Between analytic
// shapes each push-out is followed by a search.
// Impacts are located within the step: impactInside() (ContactSet) tells the World that a contact which was
// not active at the start of a substep ends it deeper than impact_tolerance; the World then undoes
// the substep and takes it as two halves (down to 1/1024 of it), so the impulse acts at a state
// at most impact_tolerance past the touching one.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "physics/constraint.h"
#include "physics/constraint_solver.h"
#include "physics/controller.h"
#include "physics/featherstone.h"
#include "physics/physics_params.h"
#include "physics/shapes.h"
#include "physics/status.h"

namespace ponyhop {

class World;

struct CollisionParams {
  double friction = 0.5;           // Coulomb's mu (both static and kinetic)
  double restitution = 0.0;        // e: normal velocity after / before an impact
  double margin = 0.0;             // m, every shape is inflated by this skin
  double impact_tolerance = 1e-4;  // m, a new contact this deep at the end of a substep splits it
};

struct CollisionStats {
  int active = 0;                   // contact and limit rows' constraints active after the last stage
  double deepest = 0.0;             // m, deepest contact overlap found by the last stage (before pushing out)
  double overshoot = 0.0;           // rad, furthest a joint limit was passed at the last stage
  double max_energy_gain = -1e300;  // J, kinetic energy after - before the impulses, any stage
  int impacts = 0;                  // stages with at least one newly touching contact
  int iterations = 0;               // projected Gauss-Seidel sweeps of the last stage (impulses + push-outs)
  // Since construction (per step: the difference over the step).
  long queries = 0;  // distance-field evaluations of the narrow phase
  long sweeps = 0;   // projected Gauss-Seidel sweeps
  long capped = 0;   // solves stopped at the sweep cap before their tolerance
  // Substeps accepted although a link moved further against a distance grid than the check
  // between two stages allows (the World's splits ran out: 1/1024 of a substep); 0 keeps the
  // promise that nothing passes through (docs/PHYSICS.md, "No pass-through").
  long too_fast = 0;
};

class Collisions final : public ContactSet, public std::enable_shared_from_this<Collisions> {
 public:
  explicit Collisions(const CollisionParams& params, SolverKind solver = SolverKind::Dense);

  // A shape on a body (kWorldBody: fixed in the world). Returns its index.
  int addShape(int body, Shape shape);
  // The pair (a, b) collides; per-pair friction and restitution (negative: the params').
  void addPair(int shape_a, int shape_b, double friction = -1.0, double restitution = -1.0);
  // A swing cone between body `parent`'s axis and `child`'s axis (body-frame unit vectors), angle
  // in radians; kWorldBody parent: a fixed world axis.
  void addConeLimit(int parent, const Eigen::Vector3d& parent_axis, int child, const Eigen::Vector3d& child_axis,
                    double max_angle);
  // A twist limit: the child's turn about its axis relative to the parent, |twist| <= max_angle,
  // measured from the relative orientation at the time of the call (the rest pose).
  void addTwistLimit(int parent, int child, const Eigen::Vector3d& child_axis, double max_angle,
                     const std::vector<RigidBody>& bodies);

  // Adds this set to the world (hold it in a shared_ptr). Featherstone (reduced coordinates): the
  // stage's W_c is Phi H^-1 Phi^T J_c^T from the world's ArticulatedSystem (its impulseResponse()),
  // the push-out's joint projection its projectBodies(); everything else is the same.
  void attach(World& world);
  // ContactSet: the contact stage and the impact check on the world's bodies and joints.
  void update(World& world) override;
  bool impactInside(const World& world) const override;
  std::any saveState() const override { return memory_; }
  void restoreState(const std::any& state) override;

  // The contact stage on the state just reached (joints: the world's). Returns ok or a problem.
  Status resolve(std::vector<RigidBody>& bodies, const Constraints& joints);
  // True when a contact not active at the start of the substep now overlaps by more than
  // impact_tolerance, or when a link moved too far against a distance grid for the check to
  // bound what it passed (movedTooFar): the World splits the substep.
  bool impactIn(const std::vector<RigidBody>& bodies) const;
  // True when, since the last stage, an end of a rounded shape's core moved in the frame of a
  // distance grid it is paired with by more than half the shape's thinnest radius plus its
  // clearance from the grid at that stage (docs/PHYSICS.md, "No pass-through").
  bool movedTooFar(const std::vector<RigidBody>& bodies) const;

  const CollisionParams& params() const { return params_; }
  CollisionParams& params() { return params_; }
  const CollisionStats& stats() const { return stats_; }
  const std::vector<Shape>& shapes() const { return shapes_; }
  int shapeBody(int shape) const { return owners_[shape]; }

  // A found contact or active limit: one unilateral constraint (1 or 3 rows).
  struct Row {
    int a = kWorldBody, b = kWorldBody;               // the impulse acts + on a, - on b
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  // contacts: world point
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    bool angular = false;  // limits: rows act on rotations only (normal = the axis)
    double gap = 0.0;      // m (rad for limits)
    double mu = 0.0, e = 0.0;
    int key0 = 0, key1 = 0;  // identity for the active set (source, sub-index)
    bool grid = false;       // against a distance grid (its solve stops at the grid's accuracy)
    double feature = 0.0;    // contacts: where on the shape (ContactPoint::feature)
  };
  // Every contact and limit at the given state whose gap is below `reach`; the distance-field
  // evaluations are added to *queries when given.
  std::vector<Row> detect(const std::vector<RigidBody>& bodies, double reach, long* queries = nullptr) const;
  // detect() at the active set's reach, kept with the poses (and margin) it was found at and
  // reused while they are the same bit for bit.
  const std::vector<Row>& touching(const std::vector<RigidBody>& bodies) const;
  // The rows `found` at an earlier state measured again at the present one without a search:
  // each contact at its feature (measureAt), every limit as detect() does; those still within
  // the active set's reach. What the push-out passes see when every pair is against a grid.
  std::vector<Row> remeasure(const std::vector<RigidBody>& bodies, const std::vector<Row>& found) const;

 private:
  struct Pair {
    int a, b;
    double mu, e;
  };
  struct Limit {
    bool twist = false;
    int parent, child;
    Eigen::Vector3d parent_axis, child_axis;
    Eigen::Quaterniond rest;  // twist: parent-to-child rest rotation
    double max_angle;
  };
  // Per row block (3 rows for a contact with friction, else 1): the 6-vectors J_a, J_b.
  void buildJacobians(const std::vector<RigidBody>& bodies, const std::vector<Row>& rows, bool normals_only);
  // `factored`: a solver that already holds J_j M^-1 J_j^T factored at these bodies (the World's
  // after its stabilize), used instead of factoring solver_; null: factor solver_.
  bool buildDelassus(const std::vector<RigidBody>& bodies, const Constraints& joints,
                     const ConstraintSolver* factored = nullptr);

  CollisionParams params_;
  std::vector<Shape> shapes_;
  std::vector<int> owners_;
  std::vector<Pair> pairs_;
  std::vector<Limit> limits_;
  // What a stage tells the next (saveState()): the active set and the impulses of its contacts
  // (the next solve's warm start).
  struct Memory {
    std::set<std::pair<int, int>> active;
    std::vector<std::pair<std::pair<int, int>, Eigen::Vector3d>> impulses;  // (key0, key1) -> normal, tangents
    std::vector<Eigen::Vector3d> cores;  // per pair against a grid: the core's ends in the grid's frame
  };
  // A pair of a rounded shape and a distance grid (either order): the rounded shape's and the
  // grid's indices. False for any other pair.
  bool roundedAndGrid(const Pair& pair, int& ri, int& gi) const;
  // Per pair of a rounded shape and a distance grid (either order), in the pairs' order: its
  // core's two ends in the grid's frame, into `cores` (its storage kept).
  void coresInGrids(const std::vector<RigidBody>& bodies, std::vector<Eigen::Vector3d>& cores) const;
  // The limit k's row at the given state when its gap is below reach.
  bool limitRow(const std::vector<RigidBody>& bodies, size_t k, double reach, Row& row) const;
  // The state cache: the poses (and margin) below were computed at, reset when they change.
  struct AtState {
    std::vector<Eigen::Vector3d> x;
    std::vector<Eigen::Quaterniond> q;
    double margin = 0.0;
    bool searched = false;  // rows: touching()'s search
    std::vector<Row> rows;
    bool cored = false;  // cores: coresInGrids()
    std::vector<Eigen::Vector3d> cores;
    int too_far = -1;  // movedTooFar() against memory_.cores (-1: not yet asked)
  };
  AtState& at(const std::vector<RigidBody>& bodies) const;
  // Per pair of a rounded shape and a grid, in the pairs' order: a lower bound of its smallest gap
  // (collide()'s GridClearance) at the core ends `a`, `b` (grid frame) it was found at, when its
  // last search found nothing within reach. detect() skips the pair while the bound, less what the
  // core has moved since (times the grid's Lipschitz bound), is still beyond reach: the search
  // would find nothing (docs/PHYSICS.md, "No pass-through", 4). A fact about the geometry, so it
  // holds across restored states.
  struct Clearance {
    bool valid = false;
    double lower = 0.0;
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  };
  mutable std::vector<Clearance> clearances_;
  const std::vector<Eigen::Vector3d>& coresAt(const std::vector<RigidBody>& bodies) const;
  Memory memory_;
  mutable CollisionStats stats_;  // touching() counts its queries
  std::unique_ptr<ConstraintSolver> solver_;
  ArticulatedSystem* reduced_ = nullptr;  // during update() on a featherstone world: its tree
  std::vector<ArticulatedSystem::ImpulseRow> reduced_rows_;
  const char* singularMessage() const {
    return reduced_ ? "the joint-space mass matrix is not positive definite"
                    : "the joints' constraint matrix is singular";
  }
  SolverKind kind_;
  // update(): the World's solver when its stabilize factored the joints at the state the stage
  // starts from (World::solverFactoredAt), for the impulses' Delassus build; null otherwise.
  const ConstraintSolver* world_factored_ = nullptr;
  ConstraintSystem joint_system_;

  // Scratch of one solve.
  struct JRow {
    int a, b, block;
    Vector6d ja, jb;
  };
  std::vector<JRow> jrows_;
  std::vector<std::vector<Vector6d>> w_;          // per row: W_c column (per body); rows in use first
  Eigen::VectorXd joint_rhs_, joint_y_;           // a column's joint solve: J_j M^-1 J_c^T, its multipliers
  std::vector<Vector6d> joint_corr_;              // and their mass-weighted correction
  std::vector<Eigen::Matrix3d> inverse_inertia_;  // per body: R I^-1 R^T at the Delassus build's state
  Eigen::MatrixXd delassus_, normal_d_;           // D; the push-out's normal rows of it (swapped in)
  mutable AtState at_;
  mutable bool at_valid_ = false;
  bool grid_only_ = false;  // every pair is against a distance grid (the push-out remeasures)
};

}  // namespace ponyhop

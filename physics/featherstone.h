// Reduced (joint) coordinates for tree-shaped systems (Featherstone 2008; John survey, "Recursive
// Newton-Euler", "Composite Rigid-Body", "Articulated-Body Algorithm"): physics.solver =
// featherstone. The state is kept in joint coordinates, so joints hold by construction (no
// drift, nothing to stabilize); the maximal-coordinate bodies (x, q, v, w) are written back after
// every evaluation for drawing, energy, force elements and output.
//
// Joint coordinates and speeds (node i = one dynamic body and the joint to its parent):
//   free root   (a dynamic body with no joint to the world or a kinematic body): x, q of the body;
//               u = [v; w] (world frame, centre of mass). 6 dofs.
//   spherical   Q = q_p^-1 q_i (a unit quaternion, child relative to parent); u = omega, the
//               relative angular velocity in the parent's frame: w_i = w_p + R_p omega and
//               Q' = 1/2 (0, omega) Q. 3 dofs.
//   prismatic   s, the slide along z (fixed in the parent a); the child keeps the orientation
//               q_i = q_p Q0 and x_i = x_p + R_p (e + s z). 1 dof.
// The parent of a root joint may be the world or a kinematic body (the chain's anchor, the head):
// its prescribed velocity and acceleration enter as the base motion.
//
// Spatial quantities are world-frame 6-vectors at each body's centre of mass: V = [v; w],
// A = [a; alpha] (the ordinary accelerations), F = [f; tau about the centre]. A joint relates
// child and parent as
//   V_i = X_i V_p + S_i u_i,    A_i = X_i A_p + S_i u_i' + c_i,    F_p = X_i^T F_i,
//   X_i = [ I  -d~ ; 0  I ],  d = x_i - x_p  (a rigid shift of the reference point),
// where S_i (6 x dofs) and the velocity-product term c_i are derived above jointKinematics() in
// featherstone.cpp. Each body obeys Newton-Euler at its centre: F = M_i A_i + b_i with
// M_i = diag(m I, I_world) and b_i = [-f_ext; w x I w - t_ext] (gravity, force elements and the
// controller's forces are the bodies' accumulators, exactly as in the multiplier path).
//
//   ABA (forward dynamics, O(n)): three passes, see forwardDynamics().
//   RNEA (inverse dynamics, O(n)): tau = S^T F^J given u'.
//   CRBA (joint-space mass matrix H = Phi^T M Phi, O(n d) for depth d): composite inertias.
// Cross-checks (tests/physics/featherstone_test.cpp): RNEA(ABA(tau)) = tau; H is SPD and
// H^-1 (tau - C) with C = RNEA(0) equals ABA; ABA's body accelerations equal the multiplier
// solvers' on the same state.
//
// Closed loops (John survey, "Dealing with Closed Loops": a spanning tree, the tree's dynamics,
// the loops mimicked by constraint forces): build() keeps a spanning tree of the joints (breadth
// first from each component's first held body) and makes every other joint a loop joint (a second
// joint reaching a placed body, a second hold on the world or a prescribed body). A loop joint's
// rows (its Constraint::evaluate: C, J_a, J_b, J'q' on the maximal bodies) are closed by
// multipliers lambda in joint space, L = J Phi (Phi: u -> the bodies' twists):
//   u' = u'_0 + H^-1 L^T lambda,   K lambda = -(J A_0 + J'q' [+ 2 alpha C' + beta^2 C]),
//   K = L H^-1 L^T,
// where u'_0, A_0 is the plain ABA and H^-1 L^T is the ABA's response to each row's unit force
// (the force-free passes over the articulated inertias the ABA has just built: closeLoops()).
// Drift of C is stabilized as for the multiplier solvers (physics.stabilization): Baumgarte in
// the right-hand side above, or projection after each step onto C = 0 and C' = 0 in the joint-space
// mass metric H (projectLoops()). Adaptive dynamics does not take loops.
//
// Contacts are not rows of the step: the contact stage (physics/collisions.h) runs after it on the
// bodies, with impulse responses in joint space (impulseResponse()).
//
// What it cannot express, reported by build() as a message naming the solver: any
// joint type other than spherical and prismatic, a prismatic joint whose sliding frame is on the
// child.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "physics/constraint.h"
#include "physics/physics_params.h"
#include "physics/rigid_body.h"
#include "physics/status.h"

namespace ponyhop {

// What World lends the reduced step at each force evaluation.
struct ReducedHooks {
  std::function<void(double t)> kinematics;  // prescribed bodies at time t
  std::function<bool()> forces;              // external + controller forces into the accumulators
};

class ArticulatedSystem {
 public:
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Motion = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;  // S, 6 x dofs

  // Tree from the world's bodies and joints. Ok or what it cannot express. Cheap to call every
  // step: rebuilds only when the bodies or joints changed.
  Status build(const std::vector<RigidBody>& bodies, const Constraints& joints);

  // Joint coordinates from the maximal bodies (initial state, or after someone changed them).
  void readState(const std::vector<RigidBody>& bodies);
  // Forward kinematics: the dynamic bodies' x, q, v, w from the joint coordinates (kinematic
  // bodies must be at the current time).
  void writeState(std::vector<RigidBody>& bodies) const;

  // ABA. Uses the bodies' accumulated forces and the kinematic bodies' accelerations; writes
  // every dynamic body's a, alpha and constraint force/torque; returns u' for the generalized
  // forces tau (zero if empty). The bodies must be written (writeState) at the current state.
  Eigen::VectorXd forwardDynamics(std::vector<RigidBody>& bodies, const Eigen::VectorXd& tau = {});
  // RNEA: the generalized forces that produce u' with the bodies' accumulated forces.
  Eigen::VectorXd inverseDynamics(const std::vector<RigidBody>& bodies, const Eigen::VectorXd& udot) const;
  // CRBA: the joint-space mass matrix H (dofs x dofs).
  Eigen::MatrixXd massMatrix(const std::vector<RigidBody>& bodies) const;

  // One step of size h from time t in joint space (rk4 or symplectic_euler), then the bodies
  // written back at t + h. Ok or what went wrong.
  Status step(double t, double h, Integrator integrator, std::vector<RigidBody>& bodies, const ReducedHooks& hooks);
  // The force evaluation at time t without stepping (World::evaluate).
  Status evaluate(double t, std::vector<RigidBody>& bodies, const ReducedHooks& hooks);

  // Contacts (physics/collisions.h; docs/SOLVERS.md, "Contacts"). A row is a unit impulse: the
  // wrench ja on body a and jb on body b (world frame, about each body's centre; an end on the
  // world or a prescribed body takes nothing). out[k][body] = Phi H^-1 Phi^T J_k^T, the velocity
  // change of every body (zero for bodies outside the tree) for row k, over all joints (a joint
  // rigid under adaptive dynamics takes the impulse like any other: the next step's choice sees the
  // speeds). By the articulated inertias at the bodies as they are (impulse propagation): O(n) once
  // per call and O(n) per row, no dense H. False when a joint's D = S^T I^A S is not positive
  // definite.
  struct ImpulseRow {
    int a = kWorldBody, b = kWorldBody;
    Vector6d ja = Vector6d::Zero(), jb = Vector6d::Zero();
  };
  bool impulseResponse(const std::vector<RigidBody>& bodies, const std::vector<ImpulseRow>& rows,
                       std::vector<std::vector<Vector6d>>& out) const;
  // The same by a dense Cholesky of H (O(n^3)): the tests' reference.
  bool impulseResponseDense(const std::vector<RigidBody>& bodies, const std::vector<ImpulseRow>& rows,
                            std::vector<std::vector<Vector6d>>& out) const;
  // The bodies put back on the joints after someone moved them (a contact's push-out): the joint
  // coordinates and speeds read from them, then the bodies written (kinematic bodies must be at
  // the current time).
  void projectBodies(std::vector<RigidBody>& bodies) {
    readState(bodies);
    writeState(bodies);
  }

  // Loop closure (closed loops, above): the drift correction of the loop joints' rows.
  void setLoopStabilization(Stabilization stabilization, double baumgarte_alpha, double baumgarte_beta);
  int loopRows() const { return loop_rows_; }  // rows of the loop joints (0 for a tree)

  int dofs() const { return dofs_; }
  int nodeCount() const { return static_cast<int>(nodes_.size()); }
  int nodeBody(int node) const { return nodes_[node].body; }  // the body a node moves
  const Eigen::VectorXd& velocities() const { return u_; }

  // Adaptive dynamics (physics.adaptive_joints, physics.adaptive_tolerance; docs/SOLVERS.md,
  // "Adaptive dynamics"). At the start of every step each joint gets a score, the kinetic energy
  // of its relative motion plus h^2 times that of its relative acceleration, both weighted by the
  // articulated inertia D = S^T I^A S it drives (a rigid joint scores the acceleration it would
  // have if it alone were freed). At most `budget` joints (0 = no cap) whose score is above
  // `tolerance` (J; 0 = only the round-off floor) move; every other joint is rigid for the step:
  // u = 0, u' = 0; each rigid stretch is stepped as one composite body (formComposites()). A joint that turns rigid is
  // locked by an internal impulse (momentum kept, kinetic energy never rises: lock()). Off (every joint moves, the
  // plain ABA step to the bit) when tolerance = 0 and budget is 0 or at least jointCount().
  void setAdaptive(int budget, double tolerance);
  bool adaptive() const { return adaptive_; }
  int jointCount() const { return joint_count_; }  // spherical and prismatic joints (a free root is none)
  int activeJoints() const;                        // joints that moved in the last step
  // Bodies the last adaptive step's ABA and integrator ran over: the composites of its tree (one
  // per active joint and per free root; a stretch welded to a prescribed parent is not stepped).
  int steppedBodies() const { return adaptive_ && sub_ ? sub_->nodeCount() : nodeCount(); }
  // Per node: 1 when its joint moved in the last step (a free root always does).
  std::vector<char> activeNodes() const;
  // The switch: the joints of the nodes with active[i] = 0 become rigid. Their relative speeds are
  // removed by impulses at those joints alone (H du = S_L^T lambda, du_L = -u_L): the system's
  // momentum is unchanged and its kinetic energy (relative to a prescribed base) cannot rise. The
  // bodies are written at the new speeds; kinematic bodies must be at the current time.
  void lock(std::vector<RigidBody>& bodies, const std::vector<char>& active);
  // Diagnostics only (the bench's oracles, docs/bench/adaptive.md, "Oracles"; no scene field sets
  // it): a chooser replaces the candidates and the score. At the start of every step (period 1) it
  // gets the time, the system (depths, speeds), and the full model's joint accelerations u' at the
  // current state (the ABA with every joint free: the rigid joints, at zero relative speed, are in
  // the full model's state), and fills `active` per node (free roots move whatever it says; the
  // budget is not applied to its set). The lock and the composite step are the shipped ones.
  // Needs setAdaptive() on; empty: the score.
  using Chooser = std::function<void(double t, const ArticulatedSystem& system, const Eigen::VectorXd& full_udot,
                                     std::vector<char>& active)>;
  void setChooser(Chooser chooser) { chooser_ = std::move(chooser); }
  int nodeDepth(int node) const { return depth_[node]; }  // joints between the node's and its root (0 at a root)
  int nodeDof(int node) const { return nodes_[node].dof; }
  int nodeDofs(int node) const { return nodes_[node].dofs; }
  bool nodeIsJoint(int node) const { return nodes_[node].type != Type::Free; }

 private:
  enum class Type { Free, Spherical, Prismatic };
  struct Node {
    Type type = Type::Free;
    int body = -1;            // the child body
    int parent = kWorldBody;  // parent body index (world, kinematic or dynamic)
    int parent_node = -1;     // node of the parent when it is dynamic
    int dof = 0;              // first index in u
    int dofs = 0;
    Eigen::Vector3d point_parent = Eigen::Vector3d::Zero();    // spherical: in the parent's frame
    Eigen::Vector3d point_child = Eigen::Vector3d::Zero();     // spherical: in the child's frame
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();          // prismatic: e (parent frame)
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();           // prismatic: z (parent frame)
    Eigen::Quaterniond rest = Eigen::Quaterniond::Identity();  // prismatic: Q0
    std::vector<int> children;
  };
  // Joint coordinates (per node): x (free), q (free: body; spherical: Q), s (prismatic).
  struct Coordinates {
    std::vector<Eigen::Vector3d> x;
    std::vector<Eigen::Quaterniond> q;
    std::vector<double> s;
  };
  // Per-node kinematics at the current state. S is 6 x dofs in the first columns of a fixed
  // 6 x 6 (no dynamic sizes in the passes: they are specialized on dofs = 1, 3, 6).
  struct Kinematics {
    Eigen::Matrix3d R;    // the body's rotation (body to world)
    Eigen::Matrix3d Rp;   // spherical: the parent's rotation (S = [r_i~; I] Rp)
    Eigen::Vector3d r_i;  // spherical: the joint point from the child's centre (world)
    Eigen::Vector3d d;    // x_i - x_p
    Matrix6 S;
    Vector6d c;
    Vector6d a_base;  // X A_p for a prescribed parent (zero otherwise)
  };
  // What ABA keeps per node between its passes (sized by build(): a step allocates nothing).
  struct Pass {
    Matrix6 ia;    // I^A
    Vector6d pa;   // p^A
    Matrix6 U;     // I^A S (first dofs columns)
    Matrix6 dinv;  // D^-1 (top-left dofs x dofs)
    Matrix6 d;     // D (top-left dofs x dofs; adaptive only, for the score)
    Vector6d u;    // tau - S^T p^A (first dofs)
    Vector6d acc;  // A
  };

  // A joint outside the spanning tree, closed by multipliers: its rows [row, row + rows) of K;
  // node_a, node_b: the nodes of its bodies (-1 for the world or a prescribed body).
  struct LoopJoint {
    int joint = -1;
    const Constraint* constraint = nullptr;  // refreshed by build() every step
    int node_a = -1, node_b = -1;
    int row = 0, rows = 0;
    ConstraintRows eval;  // its rows at the current state
  };
  using LoopBlock = Eigen::Matrix<double, 6, Eigen::Dynamic>;

  bool sameSignature(const std::vector<RigidBody>& bodies, const Constraints& joints) const;
  // written: the bodies are as writeState() left them (unit quaternions, used as they are) and
  // only what ABA reads is needed (a spherical joint's S is left out: ABA runs on r_i and R_p).
  void jointKinematics(const std::vector<RigidBody>& bodies, std::vector<Kinematics>& out, bool written = false) const;
  // ABA into udot (sized dofs); tau may be null. written: as for jointKinematics. forces: the
  // bodies' constraint forces as well (the joint forces F^J, one more pass); an RK4 stage whose
  // bodies the next stage overwrites leaves them out (only the last stage's reach the World).
  void aba(std::vector<RigidBody>& bodies, const Eigen::VectorXd* tau, Eigen::VectorXd& udot, bool written = false,
           bool forces = true);
  template <int D>
  void abaInward(size_t r, const Eigen::VectorXd* tau);
  template <int D>
  void abaOutward(size_t i, Eigen::VectorXd& udot);
  // u' at (t, c, u). written: the bodies already hold exactly (t, c, u) (the first stage of a
  // step after the last one wrote them): forward kinematics is not repeated.
  Status derivative(double t, const Coordinates& c, const Eigen::VectorXd& u, std::vector<RigidBody>& bodies,
                    const ReducedHooks& hooks, Eigen::VectorXd& udot, bool written = false, bool forces = true);
  // The loop joints' rows at the bodies as they are (eval of each), largest joint error.
  double evaluateLoops(const std::vector<RigidBody>& bodies);
  // After ABA's outward pass: the loop multipliers, u' and the node accelerations and joint forces
  // corrected by them. False when K is not positive definite (redundant loop rows).
  bool closeLoops(const std::vector<RigidBody>& bodies, Eigen::VectorXd& udot);
  // One pass of closeLoops() over node r / i for the loop rows [col, col + m); M = m when fixed.
  template <int D, int M>
  void loopInward(size_t r, int col, int m);
  template <int D, int M>
  void loopOutward(size_t i, int col, int m);
  // Projection of the coordinates onto the loops' C = 0, then of u onto C' = 0, in the metric H,
  // with the last closeLoops()'s H^-1 L^T and K (a chord iteration). The caller has written the
  // poses (writeParts<true, false>); the velocities are written here.
  Status projectLoops(std::vector<RigidBody>& bodies);
  // out = H^-1 L^T K^-1 rhs, with the last closeLoops()'s H^-1 L^T and factor of K.
  void loopCorrection(const Eigen::VectorXd& rhs, Eigen::VectorXd& out);
  void rates(const Coordinates& c, const Eigen::VectorXd& u, Coordinates& out) const;
  bool bodiesChanged(const std::vector<RigidBody>& bodies) const;
  void remember(const std::vector<RigidBody>& bodies);
  // Adaptive: the score of node i's joint (abaOutward) from its speed and acceleration in the
  // axes of D (world axes for a spherical joint).
  template <int D>
  void score(size_t i, const double* speed, const double* accel);
  // Adaptive, at the start of a step: scores at (t, y) with the current rigid set, the new set,
  // the lock of the joints that turned rigid. fresh: k_[0] holds u'(t, y) for the set chosen.
  Status chooseActive(double t, double h, std::vector<RigidBody>& bodies, const ReducedHooks& hooks, bool& written,
                      bool& fresh);

  // Adaptive: the composites' tree (formComposites(), compositeStep(); docs/SOLVERS.md, "Adaptive
  // dynamics").
  void allocate();
  int choicePeriod() const;
  int candidateStride() const;
  void formComposites(const std::vector<RigidBody>& bodies);
  void placeWelded(const std::vector<RigidBody>& bodies);
  Status sampleCompositeForces(std::vector<RigidBody>& bodies, const ReducedHooks& hooks);
  Status compositeStep(double t, double h, Integrator integrator, std::vector<RigidBody>& bodies,
                       const ReducedHooks& hooks);

  std::vector<int> signature_;
  Status built_;             // what build() could not express (ok when fine)
  std::vector<Node> nodes_;  // parents before children
  int dofs_ = 0;
  bool have_state_ = false;
  Coordinates coords_;
  Eigen::VectorXd u_;
  std::vector<Eigen::Matrix<double, 13, 1>> written_;  // x, q, v, w of each node's body as last written
  // Work space of a step (sized by build()).
  std::vector<Kinematics> kin_;
  // What writeState() computed on the way, for jointKinematics(written): each body's rotation
  // (from its just normalized quaternion) and a spherical joint's arms from the parent's and
  // the child's centres (world). Sized by build().
  struct Frame {
    Eigen::Matrix3d R;
    Eigen::Vector3d r_p;
    Eigen::Vector3d r_i;
  };
  mutable std::vector<Frame> frames_;
  // writeState()'s poses (and frames_) and velocities apart (featherstone.cpp).
  template <bool Positions, bool Velocities>
  void writeParts(std::vector<RigidBody>& bodies) const;
  std::vector<Pass> pass_;
  Coordinates c0_, y_, r_[4];
  Eigen::VectorXd u0_, us_, k_[4];
  bool stopped_ = false;  // the last derivative's force hook stopped the world
  // Adaptive dynamics (setAdaptive()).
  int budget_ = 0;
  double tolerance_ = 0.0;
  bool adaptive_ = false;
  int joint_count_ = 0;
  double score_h_ = 0.0;                                            // the step the scores look ahead by (s)
  std::vector<char> rigid_;                                         // per node: the joint is rigid this step
  std::vector<double> score_;                                       // per node (J), from the last ABA while adaptive
  std::vector<int> order_;                                          // work space of the choice
  std::vector<int> depth_;                                          // per node: joints above it (0 at a root)
  std::vector<char> active_;                                        // work space of the choice: the set chosen
  Eigen::VectorXd lock_tau_;                                        // work space of lock(): H w, then the speed change
  double written_time_ = std::numeric_limits<double>::quiet_NaN();  // time of the bodies step() wrote last
  // A rigid stretch as one body: the stretch's root node, its body in sub_bodies_, its frame
  // (principal axes) and centre in the root link's frame; for the joint above it, the parent
  // link's frame in the parent composite's frame (q', x'; a welded composite: its own pose in
  // its prescribed base's frame); its nodes composite_nodes_[first, first + count); the forces
  // of the step (world force, torque about the centre in its frame).
  struct Composite {
    int node = -1;
    int sub_body = -1;
    bool welded = false;    // the root's joint is rigid on a prescribed parent: moves with it
    int base = kWorldBody;  // welded: the base in sub_bodies_
    Eigen::Quaterniond frame = Eigen::Quaterniond::Identity();
    Eigen::Vector3d com = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q_parent = Eigen::Quaterniond::Identity();
    Eigen::Vector3d x_parent = Eigen::Vector3d::Zero();
    int first = 0, count = 0;
    Eigen::Vector3d force = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  };
  std::vector<Composite> composites_;
  std::vector<int> composite_of_;                    // per node: its composite
  std::vector<int> composite_nodes_;                 // the composites' nodes, composite by composite
  std::vector<int> composite_count_;                 // work space of formComposites()
  std::vector<int> sub_composite_;                   // per node of sub_: its composite
  std::unique_ptr<ArticulatedSystem> sub_;           // the composites' tree (active joints only)
  std::vector<RigidBody> sub_bodies_;                // its bodies: the composites, then prescribed copies
  std::vector<std::pair<int, int>> sub_prescribed_;  // (real body, its copy in sub_bodies_)
  bool composites_formed_ = false;
  int until_choice_ = 0;  // steps until the next choice
  Chooser chooser_;       // diagnostics: replaces the candidates and the score (setChooser())
  // Closed loops (sized by build()).
  std::vector<LoopJoint> loops_;
  int loop_rows_ = 0;
  Stabilization loop_stabilization_ = Stabilization::Projection;
  double loop_alpha_ = 0.0, loop_beta_ = 0.0;
  bool loop_failed_ = false;         // the last closeLoops() met a singular K
  std::vector<LoopBlock> loop_pa_;   // per node: the p^A of each row's unit force (6 x loop rows)
  std::vector<LoopBlock> loop_u_;    // per node: u = -S^T p^A of each row (first dofs rows)
  std::vector<LoopBlock> loop_acc_;  // per node: the acceleration A of each row
  Eigen::MatrixXd loop_y_;           // H^-1 L^T (dofs x loop rows)
  Eigen::MatrixXd loop_k_;           // K = L H^-1 L^T
  Eigen::LLT<Eigen::MatrixXd> loop_llt_;
  Eigen::LLT<Eigen::Matrix3d> loop_llt3_;  // K's factor when loop_rows_ == 3 (one spherical loop joint)
  Eigen::VectorXd loop_rhs_, loop_lambda_, loop_step_;
  // Work space of impulseResponse() (kept between contact stages: a steady stage allocates little).
  struct ImpulseWork {
    std::vector<int> node_of, path;
    std::vector<Kinematics> kin;
    std::vector<Matrix6> ia;
    std::vector<Matrix6> U;     // I^A S (first dofs columns)
    std::vector<Matrix6> dinv;  // D^-1 (top-left dofs x dofs)
    std::vector<Vector6d> pa, u, acc;
  };
  mutable ImpulseWork impulse_work_;
};

}  // namespace ponyhop

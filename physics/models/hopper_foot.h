// The foot against the ground: an active-set Lagrange-multiplier contact (in the spirit of the
// method, exact; why this and not a stiff spring: docs/HOPPER.md). The ground is the plane z = 0,
// or a terrain of boxes on it (physics/models/terrain.h) met through the tangent plane under the toe,
// n . y = level (n = +z, level = 0 on the plane; the formulas below are written for it).
//
// The foot's toe is a sphere (centre c fixed in the foot, radius rho). Its contact is one
// Constraint whose rows change with its mode (the active set):
//
//   Off    no rows.
//   Stick  C = c - anchor (3 rows: the sphere's centre held where it landed, anchor_z = rho:
//          the spherical joint's rows against the world, physics/spherical_joint.cpp), plus a
//          torsion row C = x_f . g (x_f the foot's x axis, g a horizontal world vector with
//          x_f . g = 0 at touchdown; the dot-product row of physics/prismatic_joint.cpp) while
//          torsional friction holds. lambda = (friction x, friction y, normal, twist torque).
//   Slide  C = n . c - level - rho (1 row, the normal force N); kinetic friction mu N against the
//          slip direction acts at the contact point (KineticFriction) with the N of the same
//          joint-force solve: the solve is linear in the friction's magnitude, so two solves give
//          the consistent N exactly (slideForces in hopper_foot.cpp).
//
// GroundContact decides the mode after every step (World's contact stage):
//   touchdown  Off and the sphere reaches the plane moving down: positions projected onto C = 0
//              (no penetration is ever left in a state), then one impulse with friction in the
//              same solve: the contact point's normal and two tangent velocities, their Delassus
//              matrix through the joints (the World's own mass-metric projection), and the cone
//              problem P_n >= 0, u_n' = 0, |P_t| <= mu P_n with P_t against the slip that remains
//              (physics/pgs.h). The impulse stops the slip: Stick at the landing point (its rows'
//              projection is that impulse, exact). It cannot: Slide on, with that impulse, which
//              only removes kinetic energy and never turns the slip around, and N and friction at
//              once (no step without friction).
//   liftoff    in contact and the normal multiplier, solved at the state just reached, is
//              N <= 0: the ground would have to pull, so the rows are dropped (unilateral).
//   slip       Stick and |lambda_t| > mu N: Slide, the slip direction opposite the friction
//              that no longer holds. Torsion: |lambda_twist| > mu N twist_radius drops the
//              torsion row for the rest of the stance.
//   re-stick   Slide and the slip velocity reversed (v_t . slip_dir <= 0): Stick where it is.
//
// Friction is a cone (an isotropic disc), as in the collision stage: the toe is a sphere, so no
// direction along the ground is special, and a pyramid's facets would steer a slip toward them.
// Cost: one extra force evaluation (a joint-force solve) per step in stick, three in slide, and
// up to six projections per touchdown. Accuracy: touchdowns are located within the step
// (locateEvents: the substep is bisected until the toe ends it at most that deep); liftoff and
// slip are resolved at the end of the substep in which they happen (up to one substep late). The
// impulse is exact for the state it acts at.
#pragma once

#include <Eigen/Core>
#include <any>
#include <memory>
#include <tuple>
#include <utility>

#include "physics/constraint.h"
#include "physics/controller.h"
#include "physics/force_elements.h"
#include "physics/models/terrain.h"
#include "physics/world.h"

namespace ponyhop {

enum class ContactMode { Off, Stick, Slide };

// Shared between the constraint, the friction element and the manager.
struct ContactState {
  ContactMode mode = ContactMode::Off;
  bool twist = false;                                        // Stick: the torsion row is active
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();          // Stick: where c is held (world)
  Eigen::Vector3d twist_ref = Eigen::Vector3d::UnitY();      // Stick: g (world, along the ground)
  Eigen::Vector3d slip_dir = Eigen::Vector3d::UnitX();       // Slide: unit direction of slip
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();         // the ground's plane under the toe (in contact)
  double level = 0.0;                                        //   n . y = level
  double normal_force = 0.0;                                 // N, last solve (0 when Off)
  Eigen::Vector3d friction_force = Eigen::Vector3d::Zero();  // N, tangential, last solve
  double twist_torque = 0.0;                                 // N m, last solve
};

class FootContact final : public Constraint {
 public:
  FootContact(int foot, const Eigen::Vector3d& center_local, double radius, std::shared_ptr<ContactState> state)
      : Constraint(foot, kWorldBody), center_(center_local), radius_(radius), state_(std::move(state)) {}

  int dimension() const override;
  const char* typeName() const override { return "contact"; }
  void evaluate(const RigidBody& a, const RigidBody& b, ConstraintRows& out) const override;
  double error(const ConstraintRows& rows) const override { return rows.C.size() ? rows.C.cwiseAbs().maxCoeff() : 0.0; }

 private:
  Eigen::Vector3d center_;
  double radius_;
  std::shared_ptr<ContactState> state_;
};

// Kinetic friction while sliding: f = -mu N slip_dir at the contact point (N solved with it:
// GroundContact::slideForces).
class KineticFriction final : public ForceElement {
 public:
  KineticFriction(int foot, const Eigen::Vector3d& center_local, double radius, double mu,
                  std::shared_ptr<ContactState> state)
      : foot_(foot), center_(center_local), radius_(radius), mu_(mu), state_(std::move(state)) {}
  void apply(std::vector<RigidBody>& bodies) const override;
  // mu N along the slip direction the contact stage fixed: constant within a step.
  bool dependsOnVelocity() const override { return false; }

 private:
  int foot_;
  Eigen::Vector3d center_;
  double radius_, mu_;
  std::shared_ptr<ContactState> state_;
};

struct ContactStats {
  int touchdowns = 0;
  int sliding_touchdowns = 0;
  int slips = 0;                              // Stick -> Slide transitions in stance
  int twist_slips = 0;                        // torsion rows dropped
  double max_touchdown_energy_gain = -1e300;  // J, kinetic energy after - before the impulse
  // m/s: over sliding landings, the largest slip speed after the impulse against the direction
  // of the slip before it (positive would be a friction impulse that reversed the slip)
  double max_slip_reversal = -1e300;
  int inconsistent_slides = 0;  // slide solves without a consistent N (Painleve), kept the first solve's
};

class GroundContact final : public ContactSet {
 public:
  // Adds the contact constraint and the friction element to `world` for the toe sphere of body
  // `foot` (centre in the foot's frame, radius). Contact with `terrain`, or the plane z = 0 when
  // it is null.
  GroundContact(World& world, int foot, const Eigen::Vector3d& center_local, double radius, double mu,
                double twist_radius, std::shared_ptr<const Terrain> terrain = nullptr);
  // Touchdowns located within the step (0: at the end of the step in which they happen): one
  // that ends a substep deeper than `depth` (m) splits the substep (World's bisection, to 1/1024
  // of it), so the impulse acts at most `depth` past the touching state.
  void locateEvents(double depth) { impact_tolerance_ = depth; }

  // The contact stage (World calls it after each accepted substep).
  void update(World& world) override;
  bool impactInside(const World& world) const override;
  // The active set and the counters (what update() changes).
  std::any saveState() const override { return std::pair<ContactState, ContactStats>(*state_, stats_); }
  void restoreState(const std::any& s) override {
    std::tie(*state_, stats_) = std::any_cast<const std::pair<ContactState, ContactStats>&>(s);
  }

  bool inContact() const { return state_->mode != ContactMode::Off; }
  const ContactState& state() const { return *state_; }
  const ContactStats& stats() const { return stats_; }
  int jointIndex() const { return joint_; }
  Eigen::Vector3d center(const World& world) const { return world.body(foot_).pointToWorld(center_); }
  // The toe sphere's point against the ground (in stance the contact point; in flight its lowest point).
  Eigen::Vector3d point(const World& world) const {
    return center(world) - radius_ * (inContact() ? state_->normal : Eigen::Vector3d::UnitZ());
  }
  const Terrain* terrain() const { return terrain_.get(); }
  // The height of the ground under the toe in stance (exactly 0 on the plane z = 0), else 0.
  double groundHeight(const World& world) const {
    if (!inContact()) return 0.0;
    if (state_->normal == Eigen::Vector3d::UnitZ()) return state_->level;  // a level face: exact
    return point(world).z();
  }

 private:
  void touchdown(World& world, const Terrain::Surface& ground);
  // The plane under the toe: the terrain's, or z = 0.
  Terrain::Surface groundAt(const Eigen::Vector3d& c) const;
  // The toe's centre moved along the ground's normal to rest on it (exact on the plane z = 0).
  Eigen::Vector3d onGround(const Eigen::Vector3d& c) const;
  void checkForces(World& world);
  void checkSlide(World& world, int row);
  // Slide: the normal force N and the kinetic friction mu N solved together at the current state.
  void slideForces(World& world);
  // The touchdown impulse with friction in the same solve (hopper_foot.cpp): applied to the
  // velocities; `sticks` when it stops the slip inside the cone.
  struct Impact {
    Eigen::Vector3d slip = Eigen::Vector3d::Zero();      // tangential velocity of the contact point after
    Eigen::Vector3d approach = Eigen::Vector3d::Zero();  // ... and before
    bool sticks = true;
  };
  Impact impact(World& world, bool& ok);
  // Velocities onto the joints' and the contact's velocity constraints (World's projection,
  // through its solver); returns the contact's impulse rows (empty when it has none) or sets
  // ok = false.
  Eigen::VectorXd projectVelocities(World& world, bool& ok);
  int rowOffset(const World& world) const;

  int foot_;
  Eigen::Vector3d center_;
  double radius_, mu_, twist_radius_;
  int joint_ = -1;
  std::shared_ptr<ContactState> state_;
  std::shared_ptr<const Terrain> terrain_;
  double impact_tolerance_ = 0.0;
  ContactStats stats_;
};

}  // namespace ponyhop

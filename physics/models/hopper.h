// The Raibert hopper (Hecker lecture, "Hopper Demo"; Raibert, "Legged Robots That Balance"):
// a massive body, a light upper leg hanging from it by a spherical hip, and a foot sliding in the
// upper leg on a prismatic knee, hopping on the ground plane z = 0.
//
//   body ── hip: SphericalJoint (3 rows) ── upper leg ── knee: PrismaticJoint (5 rows) ── foot
//   foot ── ground: GroundContact (0, 1, 3 or 4 rows: physics/models/hopper_foot.h)
//
// Control follows the method's split (Hecker lecture, "Think" / "ComputeControllerForces"):
//   Hopper::think(world)   once per step, first in World::step(): the state machine over the hop
//                          (FLIGHT, LOADING, COMPRESSION, THRUST, UNLOADING) and Raibert's three
//                          parts; it only changes setpoints (HopperSetpoints).
//   computeHopperForces()  the muscles: soft constraints (leg spring with thrust setpoint and end
//                          stops, hip servos) from the current state, time and setpoints only;
//                          smooth, stateless, callable at any time (RK4 stages).
// A Hopper is one of its World's controllers (physics/controller.h) and its foot contact one of
// the World's contact sets: World::step runs both; any number of hoppers share one World.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <memory>
#include <string>

#include "physics/controller.h"
#include "physics/models/hopper_foot.h"
#include "physics/models/hopper_params.h"
#include "physics/status.h"
#include "physics/world.h"

namespace ponyhop {

// What Think sets and the force law reads.
struct HopperSetpoints {
  double leg_length = 0.8;     // m, r_set of the leg spring
  double placement_x = 0.0;    // C_d of z_leg . x_body (leg direction in the body frame)
  double placement_y = 0.0;    // C_d of z_leg . y_body
  double heading = 0.0;        // rad, body yaw held in stance
  double place_weight = 1.0;   // 0..1: leg placement + leg twist servos on (flight)
  double attitude_weight = 0;  // 0..1: body attitude + heading servos on (stance)
  // N m, the most torque the stance servos may put between the body and the leg about the leg's
  // axis: what the toe's torsional friction holds (mu N twist_radius). More slips the toe, and the
  // reaction then spins the leg freely about its axis (it reached 3000 rad/s in the course).
  double yaw_torque_limit = std::numeric_limits<double>::infinity();
};

// Indices and geometry the force law needs.
struct HopperModel {
  int body = -1, upper = -1, foot = -1;
  int hip_joint = -1, knee_joint = -1;
  Eigen::Vector3d hip_in_body = Eigen::Vector3d::Zero();   // hip point, body frame
  Eigen::Vector3d hip_in_upper = Eigen::Vector3d::Zero();  // hip point, upper leg frame
  Eigen::Vector3d toe_in_foot = Eigen::Vector3d::Zero();   // toe sphere centre, foot frame
  HopperParams params;
};

// Leg length r (hip to the toe sphere's lowest point along the leg axis) and its rate r'.
struct LegState {
  double length = 0.0;
  double rate = 0.0;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // z of the upper leg: from toe toward hip
};
LegState legState(const HopperModel& m, const std::vector<RigidBody>& bodies);

// ComputeControllerForces: adds the leg spring and the hip servo forces and torques to the
// bodies' accumulators. Uses only the bodies' current state, t and the setpoints.
void computeHopperForces(const HopperModel& m, const HopperSetpoints& s, double t, std::vector<RigidBody>& bodies);

// Physical nonsense in the parameters: ok or a message naming the field.
Status validate(const HopperParams& p, const std::string& prefix = "hopper");

// The drawable pose of the hopper.
struct HopperShape {
  Eigen::Vector3d body_x = Eigen::Vector3d::Zero();
  Eigen::Quaterniond body_q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d hip = Eigen::Vector3d::Zero();
  Eigen::Vector3d upper_bottom = Eigen::Vector3d::Zero();
  Eigen::Vector3d foot_top = Eigen::Vector3d::Zero();
  Eigen::Vector3d toe = Eigen::Vector3d::Zero();  // toe sphere centre
};

class Hopper final : public Controller {
  struct Key {};  // only add() builds a Hopper

 public:
  // Builds the bodies, joints and the foot's ground contact into `world` and adds the hopper as
  // a controller (think + muscles) and its contact as a contact set: world.step() then runs it.
  // Invalid params: the world stops with the message (world.status()), nothing is built, and
  // built() is false.
  // The toe meets `terrain` (physics/models/terrain.h), or the plane z = 0 when it is null.
  static std::shared_ptr<Hopper> add(World& world, const HopperParams& params,
                                     std::shared_ptr<const Terrain> terrain = nullptr);
  Hopper(Key, World& world, const HopperParams& params, std::shared_ptr<const Terrain> terrain);

  // Think (Hecker lecture): the state machine; World::step calls it once per step, first.
  void think(World& world) override;
  // ComputeControllerForces: computeHopperForces with the current setpoints.
  void applyForces(World& world, double t) override;
  bool dependsOnVelocity() const override { return true; }  // leg and stop damping, the servos' damping
  std::any saveState() const override { return mem_; }
  void restoreState(const std::any& s) override;

  bool built() const { return contact_ != nullptr; }
  const HopperParams& params() const { return params_; }
  const HopperModel& model() const { return model_; }
  const HopperSetpoints& setpoints() const { return mem_.setpoints; }
  const GroundContact& contact() const { return *contact_; }

  HopperPhase phase() const { return mem_.phase; }
  const char* phaseName() const { return enumName(mem_.phase).data(); }
  // The command in force at time t (the script's last key with key.t <= t, else params.command).
  HopperCommand commandAt(double t) const;
  // Replaces params().command while it runs (the panel's velocity pad, height and heading): the
  // state machine keeps its phase, the next think() reads it. Returns ok or the range error
  // ("hopper.command.height = 9: must be ..."), leaving the command unchanged.
  Status setCommand(const HopperCommand& command);
  // Replaces the scripted course (the goal solve's trials; keys in time order, checked by the caller).
  void setScript(std::vector<HopperCommandKey> script) { params_.script = std::move(script); }
  bool inContact() const { return contact_->inContact(); }
  int hops() const { return mem_.hops; }              // liftoffs so far
  double lastApex() const { return mem_.last_apex; }  // m, body height at the last apex
  double thrust() const { return mem_.thrust; }       // m, last thrust setpoint extension

  LegState leg(const World& world) const { return legState(model_, world.bodies()); }
  Eigen::Vector3d footPoint(const World& world) const { return contact_->point(world); }
  // Roll, pitch, yaw (rad) of the body: R = Rz(yaw) Ry(pitch) Rx(roll).
  Eigen::Vector3d attitude(const World& world) const;
  double tilt(const World& world) const;  // rad, body z from vertical
  // Total mass and centre-of-mass velocity of body + leg.
  double mass() const;
  Eigen::Vector3d centerOfMass(const World& world) const;
  Eigen::Vector3d centerOfMassVelocity(const World& world) const;
  // Largest |C| of the knee's five rows, and of the hip's three (m).
  double kneeError(const World& world) const;
  double hipError(const World& world) const;
  HopperShape shape(const World& world) const;
  // A point at the back of the body (body frame), where a ponytail hangs.
  Eigen::Vector3d backPoint() const;

 private:
  // What think() changes: the state machine's memory and the setpoints it leaves for the force law.
  struct Memory {
    HopperSetpoints setpoints;
    HopperCommand command;  // in force when the script has no key yet (setCommand changes it)
    HopperPhase phase = HopperPhase::Flight;
    double last_time = -1.0;
    double touchdown_time = 0.0;
    double liftoff_time = 0.0;
    double liftoff_length = 1e300;
    Eigen::Vector2d liftoff_placement = Eigen::Vector2d::Zero();
    double stance_time = 0.2;
    double flight_max_z = -1e300;
    double last_apex = 0.0;
    double stance_ground = 0.0;  // m, the ground's height under the toe in the last stance (terrain)
    double thrust = 0.0;
    double height_trim = 0.0;
    Eigen::Vector2d speed_trim = Eigen::Vector2d::Zero();        // m, integral part of the foot placement
    double heading = 0.0;                                        // rad, slewed heading setpoint
    Eigen::Vector2d desired_velocity = Eigen::Vector2d::Zero();  // m/s, slewed velocity command
    int hops = 0;
    int touchdowns = 0;
  };
  void updateSetpoints(const World& world, const HopperCommand& cmd, double dt);

  HopperParams params_;
  HopperModel model_;
  std::shared_ptr<GroundContact> contact_;
  Memory mem_;
};

}  // namespace ponyhop

// What acts on a world besides its joints and force elements, called by World::step at the
// method's places (Hecker lecture, "Simulation Loop - Control"):
//
//   Controller   think(world)            once per step, before anything moves: a state machine
//                                        that changes only setpoints (the hopper's Think);
//                applyForces(world, t)   at every force evaluation (RK4 and RATTLE call it at
//                                        their stage times): adds forces and torques to the
//                                        bodies' accumulators from the current state, t and the
//                                        setpoints only; smooth, keeps no state.
//   ContactSet   update(world)           after every accepted substep (the contact stage): adds,
//                                        changes or drops its constraint rows (an active set),
//                                        may project positions and velocities (impacts).
//
// A World holds any number of each (World::addController, World::addContactSet) and hands them
// itself by reference: nothing keeps a pointer to a World, so a World may move.
// saveState/restoreState carry what think()/update() change, so that World::saveState() is a
// complete snapshot.
#pragma once

#include <any>

namespace ponyhop {

class World;

class Controller {
 public:
  virtual ~Controller() = default;
  virtual void think(World& /*world*/) {}
  virtual void applyForces(World& world, double t) = 0;
  // Whether applyForces reads velocities (servo damping): RATTLE then corrects its second kick
  // (physics/rattle.h). True unless a controller says otherwise.
  virtual bool dependsOnVelocity() const { return true; }
  virtual std::any saveState() const { return {}; }
  virtual void restoreState(const std::any& /*state*/) {}
};

class ContactSet {
 public:
  virtual ~ContactSet() = default;
  virtual void update(World& world) = 0;
  // Impacts located within the step: true when a contact that was open at the start of the
  // substep just taken is already deeper than the set's tolerance; the World then undoes the
  // substep and takes it as two halves (as deep as its step splitting goes).
  virtual bool impactInside(const World& /*world*/) const { return false; }
  virtual std::any saveState() const { return {}; }
  virtual void restoreState(const std::any& /*state*/) {}
};

}  // namespace ponyhop

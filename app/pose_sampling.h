// Every body's pose at the times asked for: steps a scene's runtime and interpolates between the
// two steps around each time (physics/body_pose.h). Used by `ponyhop sim --poses` and
// `ponyhop export`.
#pragma once

#include <string>
#include <vector>

#include "physics/body_pose.h"
#include "sim/sim.h"

namespace ponyhop {

class PoseSampler {
 public:
  explicit PoseSampler(Sim& sim);
  // The poses at time t (t not before the previous call's). A time within 1e-9 dt of a step is
  // that step's state exactly. False when the world stopped before t (sim.status() says why).
  bool at(double t, PoseFrame& out);
  // The next step's poses (t = the step's end). False when the world stopped.
  bool nextStep(PoseFrame& out);

 private:
  bool stepOnce();
  Sim& rt_;
  PoseFrame prev_, cur_;
};

// Names of the bodies for files ("link 3" -> "link_3", "hopper body" -> "hopper_body").
std::vector<std::string> bodyIds(const World& world);

}  // namespace ponyhop

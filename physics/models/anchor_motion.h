// The prescribed motion of a chain scene's anchor point (AnchorParams), as a KinematicMotion
// with analytic velocity and acceleration (the joint to the anchor needs both, Hecker lecture):
//   fixed:              p(t) = p0
//   shake:              p(t) = p0 + (0.1 sin(2 pi 1.5 t), 0, 0.05 sin(2 pi 3 t))
//   constant_velocity:  p(t) = p0 + V t
// The anchor does not rotate.
#pragma once

#include "physics/kinematic.h"
#include "physics/models/chain_params.h"

namespace ponyhop {

KinematicMotion anchorMotion(const AnchorParams& params);

}  // namespace ponyhop

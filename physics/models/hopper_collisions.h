// The hopper's body and legs as collision shapes (physics/shapes.h), as they are drawn
// (engine/scene_draw.cpp): the body's main hull a capsule along its x axis and its two side pods
// tapered capsules beside it, the upper leg and the foot's rod tapered capsules. The toe
// sphere keeps its own ground contact (physics/models/hopper_foot.h, GroundContact): the foot's capsule stops
// two toe radii above the toe's centre, so the two never touch the ground at the same place.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "physics/collisions.h"
#include "physics/models/hopper.h"

namespace ponyhop {

// A (tapered) capsule from end a (radius ra) to end b (radius rb), in a body's frame.
struct CapsuleSpan {
  Eigen::Vector3d a, b;
  double ra = 0.0, rb = 0.0;
};

// The hopper's hull in its body frame: the main hull along x, then the two side pods. One
// description for the drawing (engine/scene_draw.cpp) and the collision shapes below.
std::array<CapsuleSpan, 3> hopperHull(const HopperParams& p);

struct HopperShapes {
  int body = -1, upper = -1, foot = -1;  // shapes of the hull, the upper leg and the foot's rod
  int pods[2] = {-1, -1};                // the hull's side pods
  int toe = -1;                          // the toe sphere (against other hoppers only)
  std::vector<int> all() const { return {body, pods[0], pods[1], upper, foot, toe}; }
};

// Adds the shapes of the hopper `m` to `col` and pairs the hull, the upper leg and the foot's rod
// with each of `scenery` (the ground plane, a terrain's boxes), at the hopper's own friction.
HopperShapes addHopperShapes(Collisions& col, const HopperModel& m, const std::vector<int>& scenery);

// Pairs every shape of a with every shape of b (two hoppers that can run into each other).
void pairHoppers(Collisions& col, const HopperShapes& a, const HopperShapes& b);

}  // namespace ponyhop

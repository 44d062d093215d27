// The ponytail against its head: a signed distance grid of the head's triangles (any mesh, in the
// head's body frame), one tapered capsule per link exactly as drawn (Chain::segments), and a
// swing cone at the root (a hair tie: the first link cannot swing into the skull). Contacts and
// the cone go through Collisions (physics/collisions.h).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "physics/chain.h"
#include "physics/collisions.h"

namespace ponyhop {

struct HeadCollisionParams {
  double cell = 0.003;       // m, grid cell of the head's signed distance field
  double margin = 0.001;     // m, skin kept between a link and the head
  double friction = 0.3;     // hair on skin
  double restitution = 0.0;
  double root_cone = 75.0;   // deg, the first link's swing from its rest direction (0: none)
};

// Builds the collider from the triangles (body frame of `head_body`) and the link capsules.
// The root link is held by the cone, not by contact (its top sits on the head at the anchor).
// Returns null and sets *error when the mesh cannot make a collider.
std::shared_ptr<Collisions> makeHeadCollisions(World& world, const Chain& chain, int head_body,
                                               const std::vector<Eigen::Vector3d>& vertices,
                                               const std::vector<uint32_t>& indices, const HeadCollisionParams& params,
                                               std::string* error);

}  // namespace ponyhop

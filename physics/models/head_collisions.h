// The ponytail against its head: a signed distance grid of the head's triangles (any mesh, in the
// head's body frame), one tapered capsule per link exactly as drawn (Chain::segments), and a
// swing cone at the root (a hair tie: the first link cannot swing into the skull). Contacts and
// the cone go through Collisions (physics/collisions.h).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "physics/collisions.h"
#include "physics/models/chain.h"
#include "physics/status.h"

namespace ponyhop {

struct HeadCollisionParams {
  double cell = 0.003;    // m, grid cell of the head's signed distance field
  double margin = 0.001;  // m, skin kept between a link and the head
  double friction = 0.3;  // hair on skin
  double restitution = 0.0;
  double root_cone = 75.0;   // deg, the first link's swing from its rest direction (0: none)
  double joint_cone = 0.0;   // deg, each joint's swing: a link's axis from its parent link's (0: none)
  double joint_twist = 0.0;  // deg, each joint's twist about the child link's axis from the rest pose (0: none)
  bool self = false;         // links two or more apart collide with each other (capsule against capsule)

  template <class V>
  void reflect(V& v) {
    v("cell", cell,
      {.unit = "m",
       .min = 5e-4,
       .max = 0.05,
       .help = "Grid cell of the head's distance field (finer: closer to the mesh, slower to build)",
       .log = true});
    v("margin", margin, {.unit = "m", .min = 0, .max = 0.05, .help = "Skin kept between a link and the head"});
    v("friction", friction, {.min = 0, .max = 5, .help = "Coulomb friction of hair on the head"});
    v("restitution", restitution, {.min = 0, .max = 1, .help = "Bounce at an impact (0: none)"});
    v("root_cone", root_cone,
      {.unit = "deg",
       .min = 0,
       .max = 180,
       .help = "The first link's swing from its rest direction (a hair tie; 0: free)"});
    v("joint_cone", joint_cone,
      {.unit = "deg", .min = 0, .max = 180, .help = "Each joint's swing limit between neighbouring links (0: free)"});
    v("joint_twist", joint_twist,
      {.unit = "deg",
       .min = 0,
       .max = 180,
       .help = "Each joint's twist limit about the link from the rest pose (0: free)"});
    v("self", self, {.help = "Links two or more apart collide with each other"});
  }
};

// Builds the collider from the triangles (body frame of `head_body`) and the link capsules of
// every chain hanging from the head (each on its own: its links against the head, its own cones).
// A root link is held by the cone, not by contact (its top sits on the head at the anchor).
// Optional: a swing cone and a twist limit at every joint between links, and capsule pairs
// between links two or more apart (`self`: with several chains, also every pair of links of two
// different chains).
// The collider into `collisions`, or what failed when the mesh cannot make one.
Status makeHeadCollisions(World& world, const std::vector<const Chain*>& chains, int head_body,
                          const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices,
                          const HeadCollisionParams& params, std::shared_ptr<Collisions>& collisions);

// makeHeadCollisions keeps the last grid it built and hands it out again for the same triangles,
// cell, padding and region (a scene rebuilt for a panel edit of friction or damping does not build
// its 0.6 s grid again). Thread-safe; this empties it (the bench measures the build).
void clearHeadColliderCache();

// A place outside the process where built grids are kept between runs (sim/grid_cache.h keeps them
// as files, when PONYHOP_GRID_CACHE names a folder): each process that builds a head collider
// (every render-farm chunk, every test) then pays the grid's build once per head, not once per
// process. The key covers the triangles, the cell, the padding, the region and the builder's own
// code (a hash of its source files and the compiler, made at build time), so a stored grid is one
// this build would make, bit for bit. load fills `grid` and returns true when it has the key's grid.
class SignedDistanceGrid;
struct GridStore {
  virtual ~GridStore() = default;
  virtual bool load(uint64_t key, SignedDistanceGrid& grid) const = 0;
  virtual void save(uint64_t key, const SignedDistanceGrid& grid) const = 0;
};
// The store makeHeadCollisions looks in after its own last grid (none: nullptr, the default).
void setGridStore(std::shared_ptr<const GridStore> store);

}  // namespace ponyhop

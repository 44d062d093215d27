#include "physics/head_collisions.h"

#include <numbers>

#include "physics/mesh_sdf.h"

namespace ponyhop {

std::shared_ptr<Collisions> makeHeadCollisions(World& world, const Chain& chain, int head_body,
                                               const std::vector<Eigen::Vector3d>& vertices,
                                               const std::vector<uint32_t>& indices, const HeadCollisionParams& params,
                                               std::string* error) {
  auto grid = std::make_shared<SignedDistanceGrid>();
  // Padding: the thickest link plus a few cells, so every query near the head is inside the grid.
  double thickest = 0.0;
  for (double r : chain.radii) thickest = std::max(thickest, r);
  if (!grid->build(vertices, indices, params.cell, thickest + params.margin + 3.0 * params.cell, error)) return nullptr;
  CollisionParams cp;
  cp.friction = params.friction;
  cp.restitution = params.restitution;
  cp.margin = params.margin;
  auto col = std::make_shared<Collisions>(cp, world.params().solver);
  const int head = col->addShape(head_body, Shape::grid(grid));
  const int n = static_cast<int>(chain.links.size());
  for (int i = 1; i < n; ++i) {
    const double r_next = i + 1 < n ? chain.radii[i + 1] : chain.radii[i];
    col->addPair(col->addShape(chain.links[i], Shape::capsule(0.5 * chain.length, chain.radii[i], r_next)), head);
  }
  if (n > 0 && params.root_cone > 0.0) {
    // The rest direction of link 0's axis in the head's frame.
    const RigidBody& h = world.body(head_body);
    const Eigen::Vector3d axis = h.q.conjugate() * (world.body(chain.links[0]).q * Eigen::Vector3d::UnitZ());
    col->addConeLimit(head_body, axis, chain.links[0], Eigen::Vector3d::UnitZ(), params.root_cone * std::numbers::pi / 180.0);
  }
  return col;
}

}  // namespace ponyhop

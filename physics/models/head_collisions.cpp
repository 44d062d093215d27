#include "physics/models/head_collisions.h"

#include <mutex>
#include <numbers>

#include "physics/mesh_sdf.h"

namespace ponyhop {

namespace {

// The last grid built, and what it was built from.
struct GridCache {
  std::mutex mutex;
  uint64_t key = 0;
  std::shared_ptr<const SignedDistanceGrid> grid;
};
GridCache& gridCache() {
  static GridCache cache;
  return cache;
}

// FNV-1a over the bytes of the inputs.
uint64_t gridKey(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices, double cell,
                 double pad, const Eigen::AlignedBox3d& region) {
  uint64_t h = 1469598103934665603ull;
  const auto bytes = [&h](const void* p, size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
  };
  bytes(vertices.data(), vertices.size() * sizeof(Eigen::Vector3d));
  bytes(indices.data(), indices.size() * sizeof(uint32_t));
  const double extra[] = {cell,
                          pad,
                          region.min().x(),
                          region.min().y(),
                          region.min().z(),
                          region.max().x(),
                          region.max().y(),
                          region.max().z()};
  bytes(extra, sizeof(extra));
  return h;
}

Status cachedGrid(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices, double cell,
                  double pad, const Eigen::AlignedBox3d& region, std::shared_ptr<const SignedDistanceGrid>& out) {
  const uint64_t key = gridKey(vertices, indices, cell, pad, region);
  GridCache& cache = gridCache();
  {
    std::lock_guard<std::mutex> lock(cache.mutex);
    if (cache.grid && cache.key == key) {
      out = cache.grid;
      return {};
    }
  }
  auto grid = std::make_shared<SignedDistanceGrid>();
  if (Status s = grid->build(vertices, indices, cell, pad, 8'000'000, &region); !s.ok()) return s;
  std::lock_guard<std::mutex> lock(cache.mutex);
  cache.key = key;
  cache.grid = grid;
  out = grid;
  return {};
}

}  // namespace

void clearHeadColliderCache() {
  GridCache& cache = gridCache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  cache.grid.reset();
  cache.key = 0;
}

Status makeHeadCollisions(World& world, const std::vector<const Chain*>& chains, int head_body,
                          const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices,
                          const HeadCollisionParams& params, std::shared_ptr<Collisions>& collisions) {
  // Padding: the thickest link plus a few cells, so every query near the head is inside the grid.
  double thickest = 0.0;
  for (const Chain* chain : chains)
    for (double r : chain->radii) thickest = std::max(thickest, r);
  const double pad = thickest + params.margin + 3.0 * params.cell;
  // Only the part of the head the hair can reach: the links hang from their anchors (fixed in the
  // head's frame), so they stay within a chain's length of its anchor (a whole-body mesh's legs are
  // left out). Several chains: the box around every chain's reach.
  const RigidBody& hb = world.body(head_body);
  Eigen::AlignedBox3d region;
  for (const Chain* chain : chains) {
    const Eigen::Vector3d anchor = hb.q.conjugate() * (chain->anchor(world) - hb.x);
    const double reach = chain->length * static_cast<double>(chain->links.size()) + pad;
    region.extend(Eigen::AlignedBox3d(anchor.array() - reach, anchor.array() + reach));
  }
  std::shared_ptr<const SignedDistanceGrid> grid;
  if (Status s = cachedGrid(vertices, indices, params.cell, pad, region, grid); !s.ok()) return s;
  CollisionParams cp;
  cp.friction = params.friction;
  cp.restitution = params.restitution;
  cp.margin = params.margin;
  auto col = std::make_shared<Collisions>(cp, world.params().solver);
  const int head = col->addShape(head_body, Shape::grid(grid));
  std::vector<std::vector<int>> capsules;  // per chain, per link (-1: none)
  for (const Chain* chain : chains) {
    const int n = static_cast<int>(chain->links.size());
    std::vector<int>& own = capsules.emplace_back(static_cast<size_t>(n), -1);
    for (int i = 0; i < n; ++i) {
      const double r_next = i + 1 < n ? chain->radii[i + 1] : chain->radii[i];
      if (i > 0 || params.self)
        own[i] = col->addShape(chain->links[i], Shape::capsule(0.5 * chain->length, chain->radii[i], r_next));
      if (i > 0) col->addPair(own[i], head);
    }
    if (params.self) {
      for (int i = 0; i < n; ++i)
        for (int j = i + 2; j < n; ++j) col->addPair(own[i], own[j]);
    }
  }
  if (params.self) {
    for (size_t a = 0; a < capsules.size(); ++a)
      for (size_t b = a + 1; b < capsules.size(); ++b)
        for (int i : capsules[a])
          for (int j : capsules[b]) col->addPair(i, j);
  }
  const double deg = std::numbers::pi / 180.0;
  for (const Chain* chain : chains) {
    const int n = static_cast<int>(chain->links.size());
    for (int i = 1; i < n; ++i) {
      const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();  // a link's axis in its body frame
      if (params.joint_cone > 0.0)
        col->addConeLimit(chain->links[i - 1], z, chain->links[i], z, params.joint_cone * deg);
      if (params.joint_twist > 0.0)
        col->addTwistLimit(chain->links[i - 1], chain->links[i], z, params.joint_twist * deg, world.bodies());
    }
  }
  for (const Chain* chain : chains) {
    if (chain->links.empty() || params.root_cone <= 0.0) continue;
    // The rest direction of link 0's axis in the head's frame.
    const RigidBody& h = world.body(head_body);
    const Eigen::Vector3d axis = h.q.conjugate() * (world.body(chain->links[0]).q * Eigen::Vector3d::UnitZ());
    col->addConeLimit(head_body, axis, chain->links[0], Eigen::Vector3d::UnitZ(),
                      params.root_cone * std::numbers::pi / 180.0);
  }
  collisions = col;
  return {};
}

}  // namespace ponyhop

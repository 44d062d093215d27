#include "physics/models/head_collisions.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>
#include <utility>

#include "physics/grid_builder_hash.h"  // generated at build time (physics/CMakeLists.txt)
#include "physics/mesh_sdf.h"
#include "physics/rigid_body.h"
#include "physics/shapes.h"

namespace ponyhop {

namespace {

// The most nodes a head's collider grid may have (its build holds a distance and a triangle per node).
constexpr long kGridMaxNodes = 8'000'000;

// The last grid built, and what it was built from; the store outside the process.
struct GridCache {
  std::mutex mutex;
  uint64_t key = 0;
  std::shared_ptr<const SignedDistanceGrid> grid;
  std::shared_ptr<const GridStore> store;
};
GridCache& gridCache() {
  static GridCache cache;
  return cache;
}

// FNV-1a over the bytes of the inputs, starting from the builder's code: the hash of its source
// files (PONYHOP_GRID_BUILDER_HASH) and the compiler that built it.
uint64_t gridKey(const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices, double cell,
                 double pad, const Eigen::AlignedBox3d& region) {
  uint64_t h = 1469598103934665603ull;
  const auto bytes = [&h](const void* p, size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
  };
  const char builder[] = PONYHOP_GRID_BUILDER_HASH __VERSION__;
  bytes(builder, sizeof(builder));
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
  std::shared_ptr<const GridStore> store;
  {
    std::lock_guard<std::mutex> lock(cache.mutex);
    if (cache.grid && cache.key == key) {
      out = cache.grid;
      return {};
    }
    store = cache.store;
  }
  auto grid = std::make_shared<SignedDistanceGrid>();
  if (!store || !store->load(key, *grid)) {
    if (Status s = grid->build(vertices, indices, cell, pad, kGridMaxNodes, &region); !s.ok()) return s;
    if (store) store->save(key, *grid);
  }
  std::lock_guard<std::mutex> lock(cache.mutex);
  cache.key = key;
  cache.grid = grid;
  out = grid;
  return {};
}

// The chain is laid out straight from its anchor along chain.direction (addChain); where that
// line runs into the head, the links would start inside it and the first contact stage would push
// them out in one step (frame 0 shows hair in the skull, the next frame pops). Before t = 0, each
// link from the second on, root to tip, is turned about its top (the previous link's bottom,
// already clear) to the direction nearest its laid-out one that keeps the whole capsule at least
// the margin off the head. A link pointing straight into the surface gains no clearance from a
// small turn (the surface's normal lies along the link), so this is a search, not a step along a
// gradient: 512 directions spread evenly over the sphere (a Fibonacci lattice, about 9 degrees
// apart) taken nearest first, then bisection on the arc from the laid-out direction to the first
// clear one, to a thousandth of that arc. The root link has no capsule in the collider (its top
// sits on the head at the anchor; its cone holds it) but its bottom is the second link's top: the
// root is turned likewise until the sphere there (the second link's top radius) is clear. Links
// below a turned one follow its new bottom, keeping their direction; a link clear in no direction
// keeps its own. Returns the number of links turned; nothing is touched when no link starts
// within the margin.
int clearInitialPose(World& world, const Chain& chain, const Shape& head, int head_body, double margin) {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const double clear = margin + 1e-5;  // m: clear of the margin by 10 um, no contact starting at zero
  int turned = 0;
  const size_t n = chain.links.size();
  const double half = 0.5 * chain.length;
  for (size_t i = 0; n > 1 && i < n; ++i) {
    RigidBody& link = world.body(chain.links[i]);
    const Eigen::Vector3d top = i == 0 ? chain.anchor(world) : chain.bottom(world, static_cast<int>(i) - 1);
    // As the collider has it (makeHeadCollisions); for the root, the sphere at its bottom.
    const Shape shape = i == 0 ? Shape::sphere(chain.radii[1], Eigen::Vector3d(0.0, 0.0, -half))
                               : Shape::capsule(half, chain.radii[i], i + 1 < n ? chain.radii[i + 1] : chain.radii[i]);
    const Eigen::Vector3d u0 = -(link.q * z);  // along the link, top to bottom
    const Eigen::Quaterniond q0 = link.q;
    const RigidBody& h = world.body(head_body);
    const PlacedShape placed_head = place(head, h.x, h.q);
    // The link's pose along u (its top kept, turned from its laid-out pose by the shortest arc).
    const auto pose = [&](const Eigen::Vector3d& u) {
      link.q = (rotationBetween(u0, u) * q0).normalized();
      link.x = top + half * u;
    };
    const Eigen::Vector3d x0 = link.x;
    // Unless a link above was turned, a link that is clear keeps its pose bit for bit.
    const auto keep = [&] {
      if (turned > 0) {
        pose(u0);
      } else {
        link.q = q0;
        link.x = x0;
      }
    };
    const auto isClear = [&](const Eigen::Vector3d& u) {
      pose(u);
      std::vector<ContactPoint> contacts;
      return collide(place(shape, link.x, link.q), placed_head, clear, contacts) == 0;
    };
    if (isClear(u0)) {
      keep();
      continue;
    }
    // The lattice's directions, nearest the laid-out one first.
    constexpr int kDirections = 512;
    std::vector<std::pair<double, Eigen::Vector3d>> candidates;
    for (int k = 0; k < kDirections; ++k) {
      const double cz = 1.0 - (2.0 * k + 1.0) / kDirections;
      const double phi = k * std::numbers::pi * (3.0 - std::sqrt(5.0));
      const double rho = std::sqrt(1.0 - cz * cz);
      const Eigen::Vector3d u(rho * std::cos(phi), rho * std::sin(phi), cz);
      candidates.emplace_back(-u.dot(u0), u);
    }
    std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const Eigen::Vector3d* found = nullptr;
    for (const auto& c : candidates)
      if (isClear(c.second)) {
        found = &c.second;
        break;
      }
    if (!found) {
      keep();
      continue;
    }
    // Bisection on the arc u0 -> found: lo inside, hi clear.
    const Eigen::Quaterniond arc = rotationBetween(u0, *found);
    const Eigen::Quaterniond identity = Eigen::Quaterniond::Identity();
    double lo = 0.0, hi = 1.0;
    while (hi - lo > 1e-3) {
      const double mid = 0.5 * (lo + hi);
      (isClear(identity.slerp(mid, arc) * u0) ? hi : lo) = mid;
    }
    pose(identity.slerp(hi, arc) * u0);
    ++turned;
  }
  return turned;
}

}  // namespace

void clearHeadColliderCache() {
  GridCache& cache = gridCache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  cache.grid.reset();
  cache.key = 0;
}

void setGridStore(std::shared_ptr<const GridStore> store) {
  GridCache& cache = gridCache();
  std::lock_guard<std::mutex> lock(cache.mutex);
  cache.store = std::move(store);
}

Status makeHeadCollisions(World& world, const std::vector<const Chain*>& chains, int head_body,
                          const std::vector<Eigen::Vector3d>& vertices, const std::vector<uint32_t>& indices,
                          const HeadCollisionParams& params, std::shared_ptr<Collisions>& collisions) {
  // Padding: the thickest link plus a few cells, so every query near the head is inside the grid.
  double thickest = 0.0;
  for (const Chain* chain : chains)
    for (double r : chain->radii) thickest = std::max(thickest, r);
  // Only the part of the head the hair can reach: the links hang from their anchors (fixed in the
  // head's frame), so they stay within a chain's length of its anchor (a whole-body mesh's legs are
  // left out). Several chains: the box around every chain's reach.
  const RigidBody& hb = world.body(head_body);
  double cell = params.cell, pad = 0.0;
  Eigen::AlignedBox3d region;
  const auto reachOf = [&](double c) {
    pad = thickest + params.margin + 3.0 * c;
    region.setEmpty();
    for (const Chain* chain : chains) {
      const Eigen::Vector3d anchor = hb.q.conjugate() * (chain->anchor(world) - hb.x);
      const double reach = chain->length * static_cast<double>(chain->links.size()) + pad;
      region.extend(Eigen::AlignedBox3d(anchor.array() - reach, anchor.array() + reach));
    }
  };
  reachOf(cell);
  // A whole body whose wings or arms fill the hair's reach on every side (the Quake II faerie's)
  // can pass the grid's node limit at the scene's cell: the cell grows by a tenth at a time until
  // the grid fits, a coarser collider rather than none. A grid within the limit keeps its cell.
  for (int i = 0; i < 10 && SignedDistanceGrid::nodes(vertices, indices, cell, pad, &region) > kGridMaxNodes; ++i)
    reachOf(cell *= 1.1);
  std::shared_ptr<const SignedDistanceGrid> grid;
  if (Status s = cachedGrid(vertices, indices, cell, pad, region, grid); !s.ok()) return s;
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
  // The root cones' rest directions: the laid-out ones (chain.direction), before the poses are
  // cleared; then each chain's starting pose is cleared of the head.
  const RigidBody& hb0 = world.body(head_body);
  std::vector<Eigen::Vector3d> root_axes;
  bool moved = false;
  for (const Chain* chain : chains) {
    root_axes.push_back(chain->links.empty() ? Eigen::Vector3d::UnitZ()
                                             : Eigen::Vector3d(hb0.q.conjugate() * (world.body(chain->links[0]).q *
                                                                                    Eigen::Vector3d::UnitZ())));
    moved |= clearInitialPose(world, *chain, col->shapes()[size_t(head)], head_body, params.margin) > 0;
  }
  if (moved) world.projectVelocities();  // the moved links' velocities made consistent with the joints again
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
  for (size_t c = 0; c < chains.size(); ++c) {
    if (chains[c]->links.empty() || params.root_cone <= 0.0) continue;
    col->addConeLimit(head_body, root_axes[c], chains[c]->links[0], Eigen::Vector3d::UnitZ(),
                      params.root_cone * std::numbers::pi / 180.0);
  }
  collisions = col;
  return {};
}

}  // namespace ponyhop

#include "physics/models/chain.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "physics/force_elements.h"
#include "physics/hinge_joint.h"
#include "physics/models/anchor_motion.h"
#include "physics/rigid_body.h"
#include "physics/spherical_joint.h"
#include "physics/validate.h"

namespace ponyhop {

Status validate(const ChainParams& p, const std::string& prefix) {
  if (Status s = checkRanges(p, prefix); !s.ok()) return s;
  if (!(p.links >= 1)) return Status::error(prefix + ".links must be at least 1");
  if (!(p.length > 0.0) || !(p.mass > 0.0) || !(p.radius > 0.0) || !(p.taper > 0.0)) {
    return Status::error(prefix + ".length, .mass, .radius and .taper must be positive");
  }
  if (!(p.direction.norm() > 1e-9)) {
    return Status::error(prefix + ".direction = (0, 0, 0): must be a non-zero vector (the chain's initial direction)");
  }
  const bool servo = p.servo.stiffness > 0.0 || p.servo.damping > 0.0;
  if (servo && !(p.hinge.norm() > 1e-9)) {
    return Status::error(prefix + ".servo: a servo turns the root hinge: set " + prefix +
                         ".hinge to its axis (it is 0 0 0: a spherical root joint)");
  }
  if (p.hinge.norm() > 1e-9 && p.hinge.normalized().cross(p.direction.normalized()).norm() < 1e-6) {
    return Status::error(prefix + ".hinge is along " + prefix +
                         ".direction: the first link would lie on its own axis (the hinge must be across the link)");
  }
  return {};
}

Status validate(const AnchorParams& p, const std::string& prefix) { return checkRanges(p, prefix); }

namespace {

const RigidBody& bodyOf(const World& world, int i) { return i == kWorldBody ? worldBody() : world.body(i); }

}  // namespace

Chain addChain(World& world, const ChainParams& params, int parent, const Eigen::Vector3d& anchor_local,
               const Eigen::Vector3d& initial_velocity) {
  Chain chain;
  if (Status s = validate(params); !s.ok()) {
    world.fail(s.message());
    return chain;
  }
  if (parent != kWorldBody && (parent < 0 || parent >= world.bodyCount())) {
    world.fail("chain: parent body " + std::to_string(parent) + " does not exist");
    return chain;
  }
  const int n = params.links;
  const double len = params.length;
  chain.parent = parent;
  chain.anchor_local = anchor_local;
  chain.length = len;

  const Eigen::Vector3d d = params.direction.normalized();
  const Eigen::Vector3d p0 = chain.anchor(world);
  // Body z points from the bottom end to the top end: -d along the initial chain.
  const Eigen::Quaterniond q0 = rotationBetween(Eigen::Vector3d::UnitZ(), -d);
  const Eigen::Vector3d g = world.params().gravity;
  const Eigen::Vector3d down =
      g.norm() > 0.0 ? Eigen::Vector3d(g.normalized()) : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d half(0.0, 0.0, 0.5 * len);

  int previous = parent;
  for (int i = 0; i < n; ++i) {
    const double s = n > 1 ? static_cast<double>(i) / (n - 1) : 0.0;
    const double r = params.radius * (1.0 + (params.taper - 1.0) * s);
    RigidBody link;
    link.name = "link " + std::to_string(i);
    link.mass = params.mass * (r * r) / (params.radius * params.radius);
    const double across = link.mass * (3.0 * r * r + len * len) / 12.0;
    link.inertia = Eigen::Vector3d(across, across, 0.5 * link.mass * r * r);
    link.x = p0 + (i + 0.5) * len * d;
    link.q = q0;
    link.v = initial_velocity;
    const int id = world.addDynamicBody(link);

    // Joint: link i's top end on the anchor (i = 0) or on the previous link's bottom end.
    const Eigen::Vector3d parent_point = i == 0 ? anchor_local : Eigen::Vector3d(-half);
    if (i == 0 && params.hinge.norm() > 1e-9) {
      const Eigen::Vector3d axis = params.hinge.normalized();
      chain.joints.push_back(world.addJoint(std::make_unique<HingeJoint>(
          previous, parent_point, bodyOf(world, previous).q.conjugate() * axis, id, half, q0.conjugate() * axis)));
    } else {
      chain.joints.push_back(world.addJoint(std::make_unique<SphericalJoint>(previous, parent_point, id, half)));
    }
    // Root-to-tip curves (ratio 1: exactly the root's value at every joint).
    const double damping =
        params.damping_tip == 1.0 ? params.damping : params.damping * std::pow(params.damping_tip, s);
    const double stiffness =
        params.stiffness_tip == 1.0 ? params.stiffness : params.stiffness * std::pow(params.stiffness_tip, s);
    if (damping > 0.0) world.addForceElement(std::make_unique<JointDamper>(previous, id, damping));
    if (stiffness > 0.0) {
      const Eigen::Quaterniond rest = bodyOf(world, previous).q.conjugate() * q0;
      world.addForceElement(std::make_unique<BendingSpring>(previous, id, stiffness, rest));
    }
    if (params.drag > 0.0) world.addForceElement(std::make_unique<LinearDrag>(id, params.drag * len));

    // Reference: the centre when hanging straight down at rest from the starting anchor point.
    chain.potential_reference -= link.mass * g.dot(p0 + (i + 0.5) * len * down);
    chain.links.push_back(id);
    chain.radii.push_back(r);
    previous = id;
  }
  world.addPotentialReference(chain.potential_reference);
  world.projectVelocities();  // Kelvin: least-kinetic-energy velocities consistent with the joints
  return chain;
}

ChainWorld makeChainWorld(const PhysicsParams& physics, const ChainParams& chain, const AnchorParams& anchor) {
  ChainWorld cw{World(physics), Chain{}, -1};
  if (Status s = validate(anchor); !s.ok()) {
    cw.world.fail(s.message());
    return cw;
  }
  if (!cw.world.ok()) return cw;
  cw.anchor = cw.world.addKinematicBody(anchorMotion(anchor), "anchor");
  const Eigen::Vector3d v0 =
      anchor.motion == AnchorMotion::ConstantVelocity ? anchor.velocity : Eigen::Vector3d::Zero();
  cw.chain = addChain(cw.world, chain, cw.anchor, Eigen::Vector3d::Zero(), v0);
  return cw;
}

// ---------------------------------------------------------------------------------------------

Eigen::Vector3d Chain::anchor(const World& world) const { return bodyOf(world, parent).pointToWorld(anchor_local); }

Eigen::Vector3d Chain::top(const World& world, int i) const {
  return world.body(links[i]).pointToWorld(Eigen::Vector3d(0.0, 0.0, 0.5 * length));
}

Eigen::Vector3d Chain::bottom(const World& world, int i) const {
  return world.body(links[i]).pointToWorld(Eigen::Vector3d(0.0, 0.0, -0.5 * length));
}

Eigen::Vector3d Chain::tip(const World& world) const { return bottom(world, static_cast<int>(links.size()) - 1); }

std::vector<CapsuleSegment> Chain::segments(const World& world) const {
  std::vector<CapsuleSegment> out;
  out.reserve(links.size());
  for (size_t i = 0; i < links.size(); ++i) {
    const double r_next = i + 1 < links.size() ? radii[i + 1] : radii[i];
    out.push_back({top(world, static_cast<int>(i)), bottom(world, static_cast<int>(i)), radii[i], r_next});
  }
  return out;
}

double Chain::kineticEnergy(const World& world) const {
  double e = 0.0;
  for (int id : links) e += world.body(id).kineticEnergy();
  return e;
}

double Chain::potentialEnergy(const World& world) const {
  double e = 0.0;
  for (int id : links) e -= world.body(id).mass * world.params().gravity.dot(world.body(id).x);
  return e - potential_reference;
}

}  // namespace ponyhop

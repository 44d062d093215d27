// A chain of rigid links joined by spherical joints (the Hecker article's ponytail): built from
// ChainParams, hanging from a parent body (the kinematic head, the anchor of a chain scene, or
// later the hopper) at a point given in the parent's body frame.
//
// Link i is a solid cylinder of length L and radius r_i = r0 lerp(1, taper, i / (N - 1)), mass
// m_i = mass (r_i / r0)^2 (volume scaling), principal inertia m(3r^2 + L^2)/12 across and
// m r^2 / 2 along its axis (body z). Body frame: centre at the origin, top end at +L/2 z,
// bottom end at -L/2 z. Link 0's top end is on the anchor, each next link's top end on the
// previous bottom end; initially straight along ChainParams::direction.
//
// Energy reference: each link's potential energy is zero at its centre's height when the chain
// hangs straight down (along gravity) at rest from the anchor's starting point, so a chain
// released horizontally starts with E > 0 and a hanging one at rest has E = 0.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "physics/models/chain_params.h"
#include "physics/physics_params.h"
#include "physics/status.h"
#include "physics/world.h"

namespace ponyhop {

// A drawable piece: a tapered capsule from top to bottom.
struct CapsuleSegment {
  Eigen::Vector3d top;
  Eigen::Vector3d bottom;
  double radius_top = 0.0;
  double radius_bottom = 0.0;
};

// The chain's parts inside a World (indices), and what it knows about itself.
struct Chain {
  int parent = kWorldBody;
  Eigen::Vector3d anchor_local = Eigen::Vector3d::Zero();  // in the parent's body frame
  double length = 0.0;                                     // m, each link
  std::vector<int> links;                                  // body indices, root first
  std::vector<int> joints;           // joint indices (joint i: link i to its parent / previous link)
  std::vector<double> radii;         // m, per link
  double potential_reference = 0.0;  // J, gravity potential of the hanging-at-rest pose

  bool empty() const { return links.empty(); }
  Eigen::Vector3d anchor(const World& world) const;  // the anchor point in the world
  Eigen::Vector3d tip(const World& world) const;     // free end of the last link
  Eigen::Vector3d top(const World& world, int i) const;
  Eigen::Vector3d bottom(const World& world, int i) const;
  std::vector<CapsuleSegment> segments(const World& world) const;
  double kineticEnergy(const World& world) const;
  // Gravity only, against the reference above (bending springs: World::potentialEnergy).
  double potentialEnergy(const World& world) const;
};

// Adds the links, joints and force elements (damping, bending stiffness, drag, when non-zero)
// to `world`, hanging from body `parent` (or kWorldBody: then anchor_local is a world point).
// The links start with `initial_velocity`, then take the least-kinetic-energy velocities that
// satisfy the joints (Kelvin): a chain at rest on a moving parent starts correctly. Invalid
// params: nothing is built and the world stops with the message (world.status()).
// The first invalid field of a chain or anchor section, or ok (physics/validate.h).
Status validate(const ChainParams& p, const std::string& prefix = "chain");
Status validate(const AnchorParams& p, const std::string& prefix = "anchor");

Chain addChain(World& world, const ChainParams& params, int parent, const Eigen::Vector3d& anchor_local,
               const Eigen::Vector3d& initial_velocity = Eigen::Vector3d::Zero());

// The canonical chain scene (assets/scenes/chain.json): a kinematic anchor moving as
// AnchorParams says, the chain hanging from it. Shake: the chain is at rest at t = 0 and takes
// Kelvin's velocities. Constant velocity: the chain starts moving with the anchor (at rest in
// the anchor's frame), so the motion is the fixed-anchor motion carried along.
struct ChainWorld {
  World world;
  Chain chain;
  int anchor = -1;  // body index of the anchor
};
ChainWorld makeChainWorld(const PhysicsParams& physics, const ChainParams& chain, const AnchorParams& anchor);

}  // namespace ponyhop

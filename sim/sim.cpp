#include "sim/sim.h"

#include <cmath>

#include "physics/hinge_joint.h"
#include "physics/models/anchor_motion.h"
#include "physics/models/hopper_collisions.h"
#include "physics/models/keyframes.h"
#include "physics/spherical_joint.h"
#include "sim/grid_cache.h"
#include "sim/head_fit.h"
#include "sim/scene_io.h"

namespace ponyhop {

Sim::Sim(const Scene& scene, const AssetLoader* assets) : scene_(scene), world_(scene.physics) {
  if (!world_.ok()) throw InputError(scene_.path + ": physics: " + world_.status());
  useGridCacheFromEnvironment();
  if (scene_.head) buildHead(assets);
  if (scene_.terrain) terrain_ = std::make_shared<const Terrain>(scene_.terrain->boxes);
  buildHoppers();
  buildChains();
  // The head collider first clears the chains' starting poses of the head (turning links that
  // start inside it); the joints are assembled after, from the cleared poses, so a loop starts
  // closed (clearing after assembly would open it). The contact set joins the world last: its
  // record of the bodies' starting poses is taken from the assembled ones.
  if (scene_.collision) buildCollisions();
  if (!scene_.joints.empty() && world_.ok()) buildJoints();
  if (world_.ok()) buildServos();
  if (collisions_) collisions_->attach(world_);
  if (!world_.ok()) throw InputError(scene_.path + ": " + world_.status());
}

// The ponytail against the head: the head's triangles in its body frame make the distance grid
// (physics/models/head_collisions.h), each link's capsule as drawn collides with it, the root link is held
// by a swing cone.
// collision.ground: the hoppers' bodies and legs against the plane z = 0 and against each other,
// in the same set (the same solve) as the head's contacts when there are both.
void Sim::buildCollisions() {
  const CollisionSection& c = *scene_.collision;
  std::vector<const Chain*> on_head;  // every chain that hangs from the head collides with it
  for (size_t i = 0; i < chains_.size(); ++i)
    if (chainSection(scene_, i).attach == ChainAttach::Head) on_head.push_back(&chains_[i]);
  if (c.head && head_ && !on_head.empty()) {
    std::vector<Eigen::Vector3d> vertices;
    vertices.reserve(head_->mesh.positions.size());
    for (const auto& p : head_->mesh.positions) vertices.push_back(head_->mesh_to_body * p.cast<double>());
    if (Status s = makeHeadCollisions(world_, on_head, head_body_, vertices, head_->mesh.indices, c, collisions_);
        !s.ok()) {
      throw InputError(scene_.path + ": collision: the head's mesh makes no collider: " + s.message());
    }
  }
  if (c.ground && !hoppers_.empty()) {
    if (!collisions_) {
      CollisionParams cp;
      cp.friction = c.friction;
      cp.restitution = c.restitution;
      cp.margin = c.margin;
      collisions_ = std::make_shared<Collisions>(cp, world_.params().solver);
    }
    std::vector<int> scenery{collisions_->addShape(kWorldBody, Shape::plane(Eigen::Vector3d::UnitZ()))};
    if (terrain_)
      for (const Shape& box : terrain_->shapes()) scenery.push_back(collisions_->addShape(kWorldBody, box));
    std::vector<HopperShapes> shapes;
    for (const auto& h : hoppers_) shapes.push_back(addHopperShapes(*collisions_, h->model(), scenery));
    for (size_t i = 0; i < shapes.size(); ++i)
      for (size_t j = i + 1; j < shapes.size(); ++j) pairHoppers(*collisions_, shapes[i], shapes[j]);
  }
}

void Sim::buildHead(const AssetLoader* assets) {
  const HeadParams& h = *scene_.head;
  const std::string mesh_path = resolveScenePath(h.mesh, scene_.path);
  if (mesh_path.empty()) throw InputError(scene_.path + ": head.mesh: " + h.mesh + ": file not found");
  if (!assets) throw InputError(scene_.path + ": head.mesh: this program reads no meshes (no asset loader)");
  head_ = assets->loadHead(h, mesh_path, scene_.path);

  // The head's motion: a clip file, the mesh file's own animation, or inline keys.
  const TrackOptions options = trackOptions(h.animation);
  std::optional<KeyframeTrack> track;
  std::string source;
  std::string err;
  if (h.animation.clip == "mesh") {
    source = mesh_path;
    track = assets->loadMeshAnimation(h, mesh_path, options, &err);
  } else {
    std::vector<Keyframe> keys = h.animation.keys;
    source = "head.animation.keys";
    if (!h.animation.clip.empty()) {
      source = resolveClipPath(h.animation.clip, scene_.path);
      if (source.empty()) throw InputError(scene_.path + ": head.animation.clip: no clip \"" + h.animation.clip + "\"");
      keys = loadClipFile(source).keys;
    }
    if (keys.empty()) keys.push_back(Keyframe{});  // no animation: the head holds still at the origin
    KeyframeTrack built;
    if (Status s = KeyframeTrack::fromKeyframes(keys, options, built); s.ok()) {
      track = built;
    } else {
      err = s.message();
    }
  }
  if (!track) throw InputError(scene_.path + ": head.animation (" + source + "): " + err);
  head_body_ = world_.addKinematicBody(makeMotion(*track), "head");
}

// An anchor from the head's bounds, moved off the surface as far as the hanging ponytail needs to
// clear the head (sim/head_fit.h).
Eigen::Vector3d Sim::standOffAnchor(const ChainParams& c) const {
  const RigidBody& head = world_.body(head_body_);
  std::vector<Eigen::Vector3d> points;
  points.reserve(head_->mesh.positions.size());
  for (const auto& p : head_->mesh.positions)
    points.push_back(head.pointToWorld(head_->mesh_to_body * p.cast<double>()));
  std::vector<double> radii;
  for (int i = 0; i < c.links; ++i) {
    const double s = c.links > 1 ? double(i) / (c.links - 1) : 0.0;
    radii.push_back(c.radius * (1.0 + (c.taper - 1.0) * s));
  }
  const Eigen::Vector3d out = (head_->anchor - head_->centre).normalized();
  const double push =
      anchorStandOff(points, head.pointToWorld(head_->anchor), head.q * out, c.direction, c.length, radii);
  return head_->anchor + push * out;
}

void Sim::buildHoppers() {
  std::vector<const HopperParams*> all;
  if (scene_.hopper) all.push_back(&*scene_.hopper);
  for (const HopperSection& p : scene_.hoppers) all.push_back(&p);
  // The guide's solved commands drive the first hopper (docs/GOALS.md, "The hopper").
  HopperParams guided;
  if (!all.empty() && scene_.guide && scene_.guide->enabled && !scene_.guide->script.empty()) {
    guided = *all[0];
    guided.script = scene_.guide->script;
    all[0] = &guided;
  }
  for (size_t i = 0; i < all.size(); ++i) {
    hoppers_.push_back(Hopper::add(world_, *all[i], terrain_));
    if (!world_.ok()) {
      const bool listed = !(scene_.hopper && i == 0);
      const std::string which = listed ? "hoppers." + std::to_string(i - (scene_.hopper ? 1 : 0)) + ": " : "";
      throw InputError(scene_.path + ": " + which + world_.status());
    }
  }
}

void Sim::buildChains() {
  for (size_t i = 0; i < chainCount(scene_); ++i)
    buildChain(chainSection(scene_, i), listedChain(scene_, i), chainKey(scene_, i));
}

// `listed`: the chain's entry in `chains` (its own head point and hopper), null for `chain`.
void Sim::buildChain(const ChainSection& c, const ChainListSection* listed, const std::string& key) {
  int parent = -1;
  Eigen::Vector3d anchor_local = Eigen::Vector3d::Zero();
  Eigen::Vector3d v0 = Eigen::Vector3d::Zero();
  switch (c.attach) {
    case ChainAttach::Anchor: {
      const AnchorParams& a = *scene_.anchor;
      // One anchor body, however many chains hang from it.
      if (anchor_body_ < 0) anchor_body_ = world_.addKinematicBody(anchorMotion(a), "anchor");
      parent = anchor_body_;
      // Constant velocity: the chain starts at rest in the anchor's frame (Galilean invariance).
      if (a.motion == AnchorMotion::ConstantVelocity) v0 = a.velocity;
      break;
    }
    case ChainAttach::Head:
      parent = head_body_;
      if (listed) {
        anchor_local = head_->mesh_to_body * listed->anchor;  // its own point, mesh coordinates
      } else {
        anchor_local = head_->anchor;
        if (scene_.head->anchor_space == AnchorSpace::Bounds) anchor_local = standOffAnchor(c);
      }
      break;
    case ChainAttach::Hopper: {
      const Hopper* h = hopper(listed ? size_t(listed->hopper) : 0);
      if (!h || !h->built()) throw InputError(scene_.path + ": " + key + ".attach: \"hopper\" needs a hopper section");
      // Two-way coupled: the chain hangs from the hopper's body, at the back.
      parent = h->model().body;
      anchor_local = h->backPoint();
      v0 = world_.body(parent).v;
      break;
    }
  }
  // A listed chain's field named as the scene has it (chains.1.links, not chain.links).
  if (Status s = validate(c, key); listed && !s.ok()) throw InputError(scene_.path + ": " + s.message());
  chains_.push_back(addChain(world_, c, parent, anchor_local, v0));
  const Chain& built = chains_.back();
  if (!listed && scene_.guide && scene_.guide->enabled && !built.empty()) {
    // The guide torques drive the scene's `chain` (docs/GOALS.md). Joint j turns link j against
    // link j - 1 (the root joint against the chain's parent).
    std::vector<int> parents{built.parent};
    parents.insert(parents.end(), built.links.begin(), built.links.end() - 1);
    guide_ = std::make_shared<GuideTorques>(built.links, parents);
    guide_->set(*scene_.guide);
    world_.addController(guide_);
  }
  // Unique body names (the --poses and export ids): a listed chain's links are "chains.N link i".
  if (listed)
    for (int id : chains_.back().links) world_.body(id).name = key + " " + world_.body(id).name;
}

// The scene's joints (closed loops): each end's body and point, then the bodies moved onto the
// joints (assembly: the position projection of physics/stabilization.h, damped Newton steps of at
// most 1 cm with the least-norm correction, until every joint meets to 1e-12 m) and given the least-kinetic-energy
// velocities that satisfy them. A loop whose points cannot meet is refused with each unclosed joint
// and its gap; a joint that repeats what others hold (redundant rows: a singular system) likewise.
void Sim::buildJoints() {
  const auto end = [this](const JointEnd& e, Eigen::Vector3d& local) {
    switch (e.body) {
      case JointBody::World:
        local = e.point;
        return kWorldBody;
      case JointBody::Head:
        local = head_->mesh_to_body * e.point;
        return head_body_;
      case JointBody::Chain: {
        const Chain& c = chains_[size_t(e.chain)];
        local = Eigen::Vector3d(0.0, 0.0, -0.5 * c.length);  // the link's lower end
        return e.link < 0 ? c.links.back() : c.links[size_t(e.link)];
      }
      case JointBody::Hopper: {
        const HopperModel& m = hoppers_[size_t(e.hopper)]->model();
        local = e.point;
        return e.part == HopperPart::Body ? m.body : e.part == HopperPart::Upper ? m.upper : m.foot;
      }
    }
    return kWorldBody;
  };
  std::vector<double> gap0;  // m, each joint's gap before assembly
  for (const JointSection& j : scene_.joints) {
    Eigen::Vector3d pa, pb;
    const int a = end(j.a, pa), b = end(j.b, pb);
    gap0.push_back((bodyOf(world_.bodies(), a).pointToWorld(pa) - bodyOf(world_.bodies(), b).pointToWorld(pb)).norm());
    if (j.type == JointType::Hinge) {
      const Eigen::Vector3d n = j.axis.normalized();
      scene_joints_.push_back(world_.addJoint(std::make_unique<HingeJoint>(
          a, pa, bodyOf(world_.bodies(), a).q.conjugate() * n, b, pb, bodyOf(world_.bodies(), b).q.conjugate() * n)));
    } else {
      scene_joints_.push_back(world_.addJoint(std::make_unique<SphericalJoint>(a, pa, b, pb)));
    }
  }
  const auto name = [this](size_t i) {
    const std::string& n = scene_.joints[i].name;
    return "joints." + std::to_string(i) + (n.empty() ? "" : " (\"" + n + "\")");
  };
  const ProjectionResult r = world_.assembleJoints();
  std::string unclosed;
  for (size_t i = 0; i < scene_joints_.size(); ++i) {
    const Constraint& c = *world_.joints()[size_t(scene_joints_[i])];
    const double e = c.error(c.rowsAt(bodyOf(world_.bodies(), c.bodyA()), bodyOf(world_.bodies(), c.bodyB())));
    if (!(e <= 1e-6)) {  // the damped steps did not bring the points together: they cannot meet
      char buf[200];
      std::snprintf(buf, sizeof buf, "; its points are %.6g m apart at t = 0 (%.3g m after assembly)", gap0[i], e);
      unclosed += "\n  " + name(i) + ": the loop cannot close" + buf;
    }
  }
  if (!unclosed.empty()) {
    throw InputError(scene_.path +
                     ": joints: a loop that cannot close at t = 0 (the bodies between the points "
                     "cannot reach):" +
                     unclosed);
  }
  if (!r.status.ok() || r.error > 1e-9) {
    // The points met, but Newton cannot finish at the closed pose: its system is singular there.
    throw InputError(scene_.path + ": joints: redundant rows: a joint holds what the others already hold (" +
                     (r.status.ok() ? std::string("the projection stalls at a singular system") : r.status.message()) +
                     "); remove it");
  }
  world_.projectVelocities();
}

// Each chain's root-hinge servo (chain.servo), made after the assembly so that its target starts
// at the crank's assembled angle (no jump at t = 0).
void Sim::buildServos() {
  for (size_t i = 0; i < chains_.size(); ++i) {
    const ServoParams& s = chainSection(scene_, i).servo;
    if (chains_[i].empty() || !(s.stiffness > 0.0 || s.damping > 0.0)) continue;
    const auto* hinge = dynamic_cast<const HingeJoint*>(world_.joints()[size_t(chains_[i].joints.front())].get());
    if (hinge)
      world_.addController(std::make_shared<HingeServo>(world_.bodies(), *hinge, s.speed, s.stiffness, s.damping));
  }
}

bool Sim::step() {
  world_.step();  // the method's step order, controllers' Think first (physics/world.h)
  return world_.ok();
}

bool Sim::advanceTo(double t) {
  const double dt = scene_.physics.dt;
  // Half a step of slack: frame times that are multiples of dt land on a step, not one short.
  while (world_.ok() && world_.time() + 0.5 * dt <= t) step();
  return world_.ok();
}

double Sim::chainEnergy() const {
  const Chain* c = chain();
  if (!c) return 0.0;
  return c->kineticEnergy(world_) + c->potentialEnergy(world_);
}

Eigen::Vector3d Sim::followPoint(const std::string& f) const {
  const Hopper* h = hopper();
  const int hopper_body = h && h->built() ? h->model().body : -1;
  const Chain* c = chain();
  if (f == "chain" && c && !c->empty()) return world_.body(c->links.front()).x;
  if (f == "hopper" && hopper_body >= 0) return world_.body(hopper_body).x;
  if (head_body_ >= 0 && (f.empty() || f == "head")) return world_.body(head_body_).x;
  if (hopper_body >= 0) return world_.body(hopper_body).x;
  if (c) return c->anchor(world_);
  return Eigen::Vector3d::Zero();
}

Eigen::Vector3d Sim::trackedPoint() const {
  const Chain* c = chain();
  if (c && !c->empty()) return c->tip(world_);
  if (const Hopper* h = hopper(); h && h->built()) return world_.body(h->model().body).x;
  return Eigen::Vector3d::Zero();
}

Eigen::Vector3d Sim::trackedVelocity() const {
  const Chain* c = chain();
  if (c && !c->empty()) {
    const RigidBody& b = world_.body(c->links.back());
    return b.velocityAt(c->tip(world_));
  }
  if (const Hopper* h = hopper(); h && h->built()) return world_.body(h->model().body).v;
  return Eigen::Vector3d::Zero();
}

SimSnapshot Sim::snapshot() const { return {world_.saveState()}; }

void Sim::restore(const SimSnapshot& s) { world_.restoreState(s.world); }

bool Sim::carryStateFrom(const Sim& from_sim, double time_shift) {
  const World& from = from_sim.world();
  if (!from.ok() || from.bodyCount() != world_.bodyCount() || from.joints().size() != world_.joints().size())
    return false;
  // Reduced coordinates (physics.solver = featherstone) keep their own state: not carried.
  if (from.reduced() || world_.reduced()) return false;
  for (int i = 0; i < world_.bodyCount(); ++i) {
    if (from.body(i).isDynamic() != world_.body(i).isDynamic()) return false;
  }
  for (int i = 0; i < world_.bodyCount(); ++i) {
    RigidBody& b = world_.body(i);
    if (b.isDynamic()) {
      b.state() = from.body(i).state();
    } else if (b.motion) {
      // The new world starts at its t = 0: its prescribed motions continue from time_shift.
      KinematicMotion m = b.motion;
      b.motion = [m, time_shift](double s) { return m(s + time_shift); };
      b.setKinematicState(b.motion(0.0));
    }
  }
  // The copied pose must still satisfy the joints (an edit that moved an attachment does not).
  return world_.maxJointError() < 1e-4;
}

}  // namespace ponyhop

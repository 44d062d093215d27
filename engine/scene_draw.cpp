#include "engine/scene_draw.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "physics/hinge_joint.h"
#include "physics/models/hopper_collisions.h"

namespace ponyhop {
namespace {

Material material(const Eigen::Vector3f& color, float specular, float shininess) {
  Material m;
  m.color = color;
  m.specular = specular;
  m.shininess = shininess;
  return m;
}
Material material(const Eigen::Vector3d& color, float specular, float shininess) {
  return material(Eigen::Vector3f(color.cast<float>()), specular, shininess);
}

// Every hinge of the world (physics/hinge_joint.h) as an axle along its axis through its pivot,
// 3 radii long on each side: the four-bar's ground pivots.
void drawHinges(const World& world, double radius, const Eigen::Vector3d& color, Renderer& renderer) {
  for (const auto& joint : world.joints()) {
    const auto* h = dynamic_cast<const HingeJoint*>(joint.get());
    if (!h) continue;
    const RigidBody& a = bodyOf(world.bodies(), h->bodyA());
    const Eigen::Vector3d p = a.pointToWorld(h->pointA()), n = a.q * h->axisA();
    renderer.drawTaperedCapsule(p - 3.0 * radius * n, p + 3.0 * radius * n, 0.6 * radius, 0.6 * radius,
                                material(color, 0.6f, 80.0f));
  }
}

// The hopper: a rounded body (a fat capsule along x with a cap and two side pods), a ball at the
// hip, the upper leg as a tapered tube and the foot as a thin rod ending in a rubber toe.
void drawHopper(const Hopper& hopper, const HopperSection& p, const World& world, Renderer& renderer) {
  const HopperShape s = hopper.shape(world);
  const Material paint = material(p.body_color, 0.35f, 48.0f);
  const Material metal = material(p.leg_color, 0.7f, 90.0f);
  const Material dark = material(Eigen::Vector3f(0.18f, 0.19f, 0.21f), 0.4f, 60.0f);
  const Material rubber = material(p.foot_color, 0.08f, 12.0f);

  const Eigen::Vector3d half = 0.5 * p.body_size;
  const auto at = [&](double x, double y, double z) {
    return Eigen::Vector3d(s.body_x + s.body_q * Eigen::Vector3d(x, y, z));
  };
  const double rz = half.z();
  const auto atBody = [&](const Eigen::Vector3d& v) { return at(v.x(), v.y(), v.z()); };
  // Main hull: a capsule along the body's x axis (its collision shape too, physics/models/hopper_collisions.h),
  // squashed look from a second, overlapping capsule.
  const std::array<CapsuleSpan, 3> hull = hopperHull(p);
  renderer.drawCapsule(atBody(hull[0].a), atBody(hull[0].b), hull[0].ra, paint);
  renderer.drawCapsule(at(-(half.x() - rz) * 0.8, 0.0, 0.15 * rz), at((half.x() - rz) * 0.8, 0.0, 0.15 * rz), 0.9 * rz,
                       paint);
  // Side pods (the body's mass is spread out: its inertia is large) and a sensor dome on top.
  for (int k = 1; k <= 2; ++k)
    renderer.drawTaperedCapsule(atBody(hull[k].a), atBody(hull[k].b), hull[k].ra, hull[k].rb, dark);
  renderer.drawSphere(at(0.25 * half.x(), 0.0, 0.85 * rz), 0.45 * rz, metal);
  // Hip ball, upper leg (tube), foot (rod) and toe.
  renderer.drawSphere(s.hip, 1.35 * p.upper_radius, dark);
  renderer.drawTaperedCapsule(s.hip, s.upper_bottom, p.upper_radius, 0.8 * p.upper_radius, metal);
  renderer.drawTaperedCapsule(s.foot_top, s.toe, p.foot_radius, 0.8 * p.foot_radius, metal);
  renderer.drawSphere(s.toe, p.toe_radius, rubber);
}

}  // namespace

void SceneDraw::upload(const Sim& sim, Renderer& renderer) {
  if (renderer_ == &renderer) return;
  release();
  renderer_ = &renderer;
  if (sim.head()) head_ = renderer.upload(sim.head()->mesh);
}

void SceneDraw::release() {
  if (renderer_ && head_.valid()) renderer_->release(head_);
  head_ = MeshHandle{};
  renderer_ = nullptr;
}

void SceneDraw::draw(const Sim& sim, Renderer& renderer) const { draw(sim, renderer, sim.scene()); }

unsigned SceneDraw::parts(const Sim& sim) {
  return (sim.headBody() >= 0 ? kHead : 0u) | (sim.chain() ? kChain : 0u) | (sim.hoppers().empty() ? 0u : kHopper);
}

void SceneDraw::draw(const Sim& sim, Renderer& renderer, const Scene& drawing, unsigned hide) const {
  const Scene& scene = sim.scene();
  const World& world = sim.world();
  if (sim.terrain() && drawing.terrain) {
    const Material stone = material(drawing.terrain->color, 0.12f, 16.0f);
    for (const Shape& box : sim.terrain()->shapes()) {
      Eigen::Affine3d pose = Eigen::Affine3d::Identity();
      pose.translate(box.offset);
      pose.rotate(box.rotation);
      renderer.drawBox(pose, box.half_extents, stone, /*still=*/true);  // the terrain never moves
    }
  }
  for (size_t i = 0; i < sim.hoppers().size() && !(hide & kHopper); ++i) {
    if (sim.hoppers()[i]->built()) drawHopper(*sim.hoppers()[i], hopperSection(scene, i), world, renderer);
  }
  if (sim.headBody() >= 0 && head_.valid() && !(hide & kHead)) {
    const RigidBody& b = world.body(sim.headBody());
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.translate(b.x);
    pose.rotate(b.q);
    // A head drawn with its file's colours (sim/mesh_data.h) is not tinted by head.color.
    const Eigen::Vector3d tint = sim.head()->mesh.colors.empty() ? scene.head->color : Eigen::Vector3d(1.0, 1.0, 1.0);
    // Its hair region (head.scalp_hair) with the first chain's look (a chain's defaults without one),
    // combed from the head's centre towards the ponytail's anchor.
    const ChainSection look = chainCount(drawing) > 0 ? chainSection(drawing, 0) : ChainSection{};
    ScalpHair hair;
    hair.color = look.color.cast<float>();
    hair.shading = HairShading{float(look.hair.highlight), float(look.hair.highlight_shift)};
    const Eigen::Vector3d axis = pose.linear() * (sim.head()->anchor - sim.head()->centre);
    hair.axis = axis.norm() > 0.0 ? axis.normalized() : Eigen::Vector3d::UnitZ();
    renderer.drawMesh(head_, pose * sim.head()->mesh_to_body, material(tint, 0.18f, 24.0f), hair);
  }
  // Each chain with its look from `drawing` when that scene has the same chains (the panel's
  // applied scene), else from the sim's own.
  const bool same_chains = chainCount(drawing) == chainCount(scene);
  for (size_t i = 0; i < sim.chains().size() && !(hide & kChain); ++i)
    drawChain(sim, sim.chains()[i], chainSection(same_chains ? drawing : scene, i), renderer);
  if (drawing.render.colliders) drawColliders(sim, renderer);
  if (drawing.render.active_joints) drawActiveJoints(sim, renderer);
  if (drawing.render.goals) drawGoals(sim, drawing, renderer);
}

HairMesh SceneDraw::chainHair(const Sim& sim, const Chain& chain, const ChainSection& look) const {
  const World& world = sim.world();
  // The curve through the anchor and every link's lower end; the radius at a joint is the mean
  // of the two links', the tip a little finer than the last link.
  std::vector<Eigen::Vector3d> points{chain.anchor(world)};
  std::vector<double> radii{chain.radii.front()};
  for (size_t i = 0; i < chain.links.size(); ++i) {
    points.push_back(chain.bottom(world, int(i)));
    radii.push_back(i + 1 < chain.radii.size() ? 0.5 * (chain.radii[i] + chain.radii[i + 1]) : 0.7 * chain.radii[i]);
  }
  // The strands' frame starts from the parent body's x axis: it turns with the head.
  const int parent = chain.parent;
  const Eigen::Vector3d reference =
      parent >= 0 ? Eigen::Vector3d(world.body(parent).q * Eigen::Vector3d::UnitX()) : Eigen::Vector3d::UnitX();
  // 4 samples per link: smooth at the tail's size on screen, and half the strand triangles of 8.
  const HairCurve curve = hairCurve(points, radii, reference, 4);
  return buildHair(curve, look.hair, look.color.cast<float>(), hairStrandCount(look.hair, draft_));
}

void SceneDraw::drawChain(const Sim& sim, const Chain& chain, const ChainSection& look, Renderer& renderer) const {
  const World& world = sim.world();
  if (look.hinge.norm() > 1e-9) {
    // A chain on a root hinge is a linkage (the four-bar), not hair: each link a rigid bar, and
    // an axle through every hinge of the world (drawHinges).
    for (const CapsuleSegment& c : chain.segments(world))
      renderer.drawTaperedCapsule(c.top, c.bottom, c.radius_top, c.radius_bottom, material(look.color, 0.45f, 48.0f));
    drawHinges(world, chain.radii.front(), look.hair.tie_color, renderer);
    return;
  }
  renderer.drawHair(chainHair(sim, chain, look));
  // The hair tie: a short band around the root, along the first link.
  const Eigen::Vector3d root = chain.anchor(world);
  const Eigen::Vector3d axis = (chain.bottom(world, 0) - root).normalized();
  const double r = chain.radii.front();
  renderer.drawTaperedCapsule(root - 0.15 * r * axis, root + 0.45 * r * axis, 1.12 * r, 1.06 * r,
                              material(look.hair.tie_color, 0.5f, 60.0f));
}

}  // namespace ponyhop

namespace ponyhop {

namespace {

// A circle of radius r about c in the plane spanned by the unit vectors u, v.
void circle(Renderer& r, const Eigen::Vector3d& c, const Eigen::Vector3d& u, const Eigen::Vector3d& v, double radius,
            const Eigen::Vector3f& colour) {
  constexpr int kSegments = 24;
  for (int i = 0; i < kSegments; ++i) {
    const double a0 = 2.0 * std::numbers::pi * i / kSegments, a1 = 2.0 * std::numbers::pi * (i + 1) / kSegments;
    r.drawLine(c + radius * (std::cos(a0) * u + std::sin(a0) * v), c + radius * (std::cos(a1) * u + std::sin(a1) * v),
               colour);
  }
}

}  // namespace

void SceneDraw::drawColliders(const Sim& sim, Renderer& renderer) const {
  const Collisions* col = sim.collisions();
  if (!col) return;
  const Eigen::Vector3f cyan(0.1f, 0.85f, 0.95f), red(0.95f, 0.15f, 0.1f);
  const World& world = sim.world();
  for (size_t i = 0; i < col->shapes().size(); ++i) {
    const Shape& shape = col->shapes()[i];
    const int body = col->shapeBody(int(i));
    const PlacedShape p = body == kWorldBody ? place(shape, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity())
                                             : place(shape, world.body(body).x, world.body(body).q);
    const Eigen::Matrix3d R = p.pose.linear();
    const Eigen::Vector3d c = p.pose.translation(), ex = R.col(0), ey = R.col(1), ez = R.col(2);
    switch (shape.type) {
      case ShapeType::Sphere:
        circle(renderer, c, ex, ey, shape.radius, cyan);
        circle(renderer, c, ey, ez, shape.radius, cyan);
        circle(renderer, c, ez, ex, shape.radius, cyan);
        break;
      case ShapeType::Capsule: {
        // End rings, four lines along the sides (a tapered capsule's, end radius to end radius)
        // and the end spheres' outlines.
        const Eigen::Vector3d a = c + shape.half_length * ez, b = c - shape.half_length * ez;
        circle(renderer, a, ex, ey, shape.radius_a, cyan);
        circle(renderer, b, ex, ey, shape.radius_b, cyan);
        for (const Eigen::Vector3d& side : {ex, ey, Eigen::Vector3d(-ex), Eigen::Vector3d(-ey)})
          renderer.drawLine(a + shape.radius_a * side, b + shape.radius_b * side, cyan);
        circle(renderer, a, ex, ez, shape.radius_a, cyan);
        circle(renderer, b, ex, ez, shape.radius_b, cyan);
        break;
      }
      case ShapeType::Box: {
        const Eigen::Vector3d h = shape.half_extents;
        const auto corner = [&](int m) {
          return Eigen::Vector3d(c + ((m & 1) ? h.x() : -h.x()) * ex + ((m & 2) ? h.y() : -h.y()) * ey +
                                 ((m & 4) ? h.z() : -h.z()) * ez);
        };
        for (int k = 0; k < 8; ++k)
          for (int axis = 0; axis < 3; ++axis)
            if (!(k & (1 << axis))) renderer.drawLine(corner(k), corner(k | (1 << axis)), cyan);  // each edge once
        break;
      }
      case ShapeType::Plane:  // drawn as the ground
      case ShapeType::Sdf:    // the head's mesh is its picture
        break;
    }
  }
  // Contacts touching now (within the margin): a cross at the point and the normal, 5 cm.
  for (const Collisions::Row& row : col->detect(world.bodies(), col->params().margin + 1e-4)) {
    if (row.angular) continue;
    renderer.drawLine(row.point, row.point + 0.05 * row.normal, red);
    const Eigen::Vector3d u = row.normal.unitOrthogonal(), v = row.normal.cross(u);
    renderer.drawLine(row.point - 0.015 * u, row.point + 0.015 * u, red);
    renderer.drawLine(row.point - 0.015 * v, row.point + 0.015 * v, red);
  }
}

// Adaptive dynamics (docs/SOLVERS.md): where the simulation spends, joint by joint. A ring in the
// plane across the link, at its top (the joint), 1.8 link radii wide.
void SceneDraw::drawActiveJoints(const Sim& sim, Renderer& renderer) const {
  const World& world = sim.world();
  const ArticulatedSystem* system = world.reduced();
  const Chain* chain = sim.chain();
  if (!system || !chain || !system->adaptive()) return;
  std::vector<int> link(world.bodyCount(), -1);  // body -> link index
  for (size_t k = 0; k < chain->links.size(); ++k) link[chain->links[k]] = static_cast<int>(k);
  const std::vector<char> active = system->activeNodes();
  const Eigen::Vector3f orange(1.0f, 0.55f, 0.05f);
  for (int i = 0; i < system->nodeCount(); ++i) {
    const int k = link[system->nodeBody(i)];
    if (!active[i] || k < 0) continue;
    const Eigen::Vector3d top = chain->top(world, k);
    const Eigen::Vector3d axis = (chain->bottom(world, k) - top).normalized();
    const Eigen::Vector3d u = axis.unitOrthogonal();
    circle(renderer, top, u, axis.cross(u), 1.8 * chain->radii[k], orange);
  }
}

// Goal markers (docs/GOALS.md, "Markers"): a wire sphere of three great circles and a cross through
// it at the goal's target, turned with the head for frame "head"; magenta while the time is within
// kGoalNear of the goal's, a dim mauve otherwise; and on the frame at the goal's time (within half
// a frame of render.fps) a yellow line from the goal's point to the target, the miss.
void SceneDraw::drawGoals(const Sim& sim, const Scene& drawing, Renderer& renderer) const {
  constexpr double kRadius = 0.015;  // m
  const Eigen::Vector3f bright(1.0f, 0.2f, 0.9f), faint(0.5f, 0.38f, 0.5f), miss(1.0f, 0.85f, 0.1f);
  const double t = sim.time();
  const double half_frame = 0.5 / std::max(drawing.render.fps, 1.0);
  for (const Goal& goal : drawing.goals) {
    const Eigen::Vector3d c = goalTargetNow(sim, goal);
    const Eigen::Matrix3d R = goal.frame == GoalFrame::Head && sim.headBody() >= 0
                                  ? sim.world().body(sim.headBody()).q.toRotationMatrix()
                                  : Eigen::Matrix3d::Identity();
    const Eigen::Vector3d ex = R.col(0), ey = R.col(1), ez = R.col(2);
    const double dt = std::abs(t - goal.t);
    const Eigen::Vector3f& colour = dt <= kGoalNear ? bright : faint;
    circle(renderer, c, ex, ey, kRadius, colour);
    circle(renderer, c, ey, ez, kRadius, colour);
    circle(renderer, c, ez, ex, kRadius, colour);
    for (const Eigen::Vector3d& axis : {ex, ey, ez})
      renderer.drawLine(c - 1.6 * kRadius * axis, c + 1.6 * kRadius * axis, colour);
    Eigen::Vector3d point;
    if (dt < half_frame && goalPointNow(sim, goal, point)) renderer.drawLine(point, c, miss);
  }
}

}  // namespace ponyhop

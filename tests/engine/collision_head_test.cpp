// The ponytail never passes through the head: the showcase and whip clips on the default head and
// on two meshes nobody tuned the collider for (a sphere and a box, written as OBJ files and read
// back through assimp). Measured against the mesh triangles themselves, not the collider: no
// link capsule goes deeper than 1 mm into the surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>

#include "engine/asset_loader.h"
#include "engine/mesh.h"
#include "physics/mesh_sdf.h"
#include "physics/models/head_collisions.h"
#include "physics/shapes.h"
#include "physics/triangle_distance.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

using Eigen::Vector3d;

void writeObj(const MeshData& m, const std::string& path) {
  std::ofstream f(path);
  for (const auto& p : m.positions) f << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (size_t i = 0; i < m.indices.size(); i += 3)
    f << "f " << m.indices[i] + 1 << ' ' << m.indices[i + 1] + 1 << ' ' << m.indices[i + 2] + 1 << '\n';
}

struct Result {
  double deepest = 0.0;  // m, deepest point of any link capsule (1..n-1) inside the mesh
  int frame = -1;
  int contacts_max = 0;
  double seconds = 0.0;  // wall time of the simulation with collisions
  // m/s, relative normal speed of a link's nearest point to the head at the sample it arrives on
  // the head (approaching) and at the sample it leaves (separating), the largest of each.
  double approach = 0.0, separation = 0.0;
  long too_fast = 0;  // CollisionStats::too_fast at the end
};

// The speed of the point `at` of body b along n, relative to the head's point there.
double normalSpeed(const RigidBody& b, const RigidBody& head, const Vector3d& at, const Vector3d& n) {
  return (b.v + b.w.cross(at - b.x) - head.v - head.w.cross(at - head.x)).dot(n);
}

// Plays the clip on the scene's head (or the mesh given) and measures at `rate` samples per
// second (30: the frames; 240: every step of ponytail.json).
// edit: a change to the scene before it is built (the solver, adaptive dynamics).
Result play(const std::string& mesh_path, const std::string& clip, double duration, bool collide = true,
            double rate = 30.0, const std::function<void(Scene&)>& edit = {}) {
  Scene scene = loadScene("assets/scenes/ponytail.json");
  if (edit) edit(scene);
  EXPECT_TRUE(scene.collision) << "ponytail.json collides with the head by default";
  if (!collide) scene.collision.reset();
  if (!mesh_path.empty()) {
    scene.head->mesh = mesh_path;
    scene.head->anchor_space = AnchorSpace::Bounds;  // the anchor: found on the mesh's surface
  }
  scene.head->animation.clip = clip;
  // The product's path: the scene's collision section makes the collider (sim/sim.cpp).
  Sim sim(scene, &assimpAssets());
  EXPECT_TRUE(sim.ok()) << sim.status();
  EXPECT_TRUE(sim.head() && sim.chain());
  EXPECT_EQ(sim.collisions() != nullptr, collide);
  if (!sim.head() || !sim.chain()) return {};
  const MeshData& mesh = sim.head()->mesh;
  const Eigen::Affine3d T = sim.head()->mesh_to_body;
  std::vector<Vector3d> v;
  for (const auto& p : mesh.positions) v.push_back(T * p.cast<double>());
  const Chain& chain = *sim.chain();
  // The exact distance to the triangles is needed out to the thickest link's radius (5 mm more).
  double reach = 0.0;
  for (const CapsuleSegment& s : chain.segments(sim.world()))
    reach = std::max({reach, s.radius_top + 0.005, s.radius_bottom + 0.005});
  const TriangleDistance exact(v, mesh.indices, 0.01, reach);
  Result res;
  // Per link body: touching the head at the last sample, and its nearest point's normal speed.
  std::map<int, bool> touching;
  std::map<int, double> speed;
  const int frames = static_cast<int>(std::round(duration * rate));
  for (int f = 1; f <= frames && sim.ok(); ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    sim.advanceTo(f / rate);
    res.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const RigidBody& head = sim.world().body(sim.headBody());
    if (const Collisions* col = sim.collisions()) {
      res.contacts_max = std::max(res.contacts_max, col->stats().active);
      res.too_fast = col->stats().too_fast;
      // The nearest row of each link within 2 mm; touching: within the stage's 10 um.
      std::map<int, std::pair<double, double>> nearest;  // body -> (gap, normal speed)
      for (const Collisions::Row& r : col->detect(sim.world().bodies(), 2e-3)) {
        if (r.angular || r.b != sim.headBody()) continue;
        const double u = normalSpeed(sim.world().body(r.a), head, r.point, r.normal);
        if (!nearest.count(r.a) || r.gap < nearest[r.a].first) nearest[r.a] = {r.gap, u};
      }
      for (int body : chain.links) {
        const bool now = nearest.count(body) && nearest[body].first < 1e-5;
        const double u = nearest.count(body) ? nearest[body].second : 0.0;
        if (now && !touching[body]) res.approach = std::max(res.approach, -speed[body]);
        if (!now && touching[body]) res.separation = std::max(res.separation, u);
        touching[body] = now;
        speed[body] = u;
      }
    }
    const std::vector<CapsuleSegment> segs = chain.segments(sim.world());
    for (size_t i = 1; i < segs.size(); ++i) {
      for (int k = 0; k <= 20; ++k) {
        const double s = k / 20.0;
        const Vector3d p_world = segs[i].top + s * (segs[i].bottom - segs[i].top);
        const double r = segs[i].radius_top + s * (segs[i].radius_bottom - segs[i].radius_top);
        const Vector3d p = head.q.conjugate() * (p_world - head.x);  // head body frame
        const double d = exact.signedDistance(p);
        if (r - d > res.deepest) {
          res.deepest = r - d;
          res.frame = f;
        }
      }
    }
  }
  EXPECT_TRUE(sim.ok()) << sim.status();
  return res;
}

// Seconds of each clip: the whole showcase and whip in the normal build; under ASan+UBSan (ten
// times slower, and the point there is memory and UB, not the motion) their first 3 s.
#ifdef PONYHOP_SANITIZED
constexpr double kClipSeconds = 3.0;
#else
constexpr double kClipSeconds = 10.0;
#endif

class HeadPenetration : public ::testing::TestWithParam<std::string> {};

TEST_P(HeadPenetration, NoLinkCapsuleGoesDeeperThanOneMillimetre) {
  const std::string which = GetParam();
  std::string path;
  const std::string dir = std::string(PONYHOP_TEST_OUT) + "/collision_head";
  std::filesystem::create_directories(dir);
  if (which == "sphere") {
    path = dir + "/sphere.obj";
    writeObj(makeUvSphere(1.0f, 48, 32), path);
  } else if (which == "box") {
    path = dir + "/box.obj";
    writeObj(makeBoxMesh(Eigen::Vector3f(0.8f, 1.0f, 0.9f)), path);
  }
  for (const char* clip : {"showcase", "whip"}) {
    const Result r = play(path, clip, kClipSeconds);
    std::printf("%s / %s: deepest %.3f mm (frame %d), contacts max %d, %.2f s wall for %.0f s\n", which.c_str(), clip,
                1e3 * r.deepest, r.frame, r.contacts_max, r.seconds, kClipSeconds);
    EXPECT_LT(r.deepest, 1e-3) << which << " " << clip << " frame " << r.frame;
    EXPECT_GT(r.contacts_max, 0) << "the clip never brings the hair onto the head: the test shows nothing";
  }
}

// The control: the same measurement without the collider finds the hair inside the head (the
// measurement can fail; the clips do throw the ponytail into the skull).
TEST(HeadPenetrationControl, WithoutTheColliderTheShowcaseGoesThroughTheHead) {
  const Result r = play("", "showcase", kClipSeconds, false);
  std::printf("default / showcase without the collider: deepest %.1f mm (frame %d), %.2f s wall for %.0f s\n",
              1e3 * r.deepest, r.frame, r.seconds, kClipSeconds);
  EXPECT_GT(r.deepest, 5e-3);
}

// A head far faster than the demos (issue 31): assets/animations/snap.json turns and snaps the head
// at up to 32.4 rad/s, 4.3 times the toss's peak of 7.50 rad/s (the head's angular velocity in
// `ponyhop sim --poses`). Measured after every step (240 Hz) against the triangles: no link
// capsule but the first goes 1 mm into the head (measured: never inside), no substep was accepted
// with a link moving further than the check between two stages bounds (Collisions::movedTooFar),
// and nothing pops out: the fastest a link leaves the head (1.21 m/s, relative normal speed) is
// below the fastest one arrives (3.62 m/s).
TEST(HeadStress, TheSnapClipNeitherPassesThroughNorPopsOut) {
  const Result r = play("", "snap", kClipSeconds, true, 240.0);
  std::printf(
      "snap: deepest %.3f mm (sample %d of 240 Hz), contacts max %d, arriving at most %.3f m/s, "
      "leaving at most %.3f m/s, %ld substeps too fast, %.2f s wall for %.0f s\n",
      1e3 * r.deepest, r.frame, r.contacts_max, r.approach, r.separation, r.too_fast, r.seconds, kClipSeconds);
  EXPECT_LT(r.deepest, 1e-3);
  EXPECT_EQ(r.too_fast, 0);
  EXPECT_LT(r.separation, r.approach) << "a link left the head faster than any arrived: a pop-out";
  EXPECT_GT(r.contacts_max, 0) << "the clip never brings the hair onto the head: the test shows nothing";
}

// Featherstone (reduced coordinates: the contact impulses in joint space, docs/SOLVERS.md,
// "Contacts"), every joint moving and under adaptive dynamics (4 of the 9 joints move per step, the
// rest of the chain rigid: its links still collide one by one): the first 3 s of the showcase
// (the hair on the head and the neck from the start) measured at every frame and of the snap at
// every step, as above: no link capsule but the first 1 mm into the head, no substep too fast,
// no pop-out.
class HeadPenetrationFeatherstone : public ::testing::TestWithParam<int> {};

TEST_P(HeadPenetrationFeatherstone, NoLinkCapsuleGoesDeeperThanOneMillimetre) {
  const int adaptive_joints = GetParam();
  const auto edit = [adaptive_joints](Scene& scene) {
    scene.physics.solver = SolverKind::Featherstone;
    scene.physics.adaptive_joints = adaptive_joints;
  };
  for (const char* clip : {"showcase", "snap"}) {
    const bool snap = std::string(clip) == "snap";
    if (snap && adaptive_joints > 0) continue;  // the snap once (the slowest: every step measured)
    const Result r = play("", clip, 3.0, true, snap ? 240.0 : 30.0, edit);
    std::printf(
        "featherstone (adaptive_joints %d) / %s: deepest %.3f mm (sample %d), contacts max %d, arriving at most "
        "%.3f m/s, leaving at most %.3f m/s, %ld substeps too fast, %.2f s wall for 3 s\n",
        adaptive_joints, clip, 1e3 * r.deepest, r.frame, r.contacts_max, r.approach, r.separation, r.too_fast,
        r.seconds);
    EXPECT_LT(r.deepest, 1e-3) << clip << " frame " << r.frame;
    EXPECT_EQ(r.too_fast, 0) << clip;
    EXPECT_GT(r.contacts_max, 0) << "the clip never brings the hair onto the head: the test shows nothing";
    if (snap) {
      EXPECT_LT(r.separation, r.approach) << "a link left the head faster than any arrived: a pop-out";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Solver, HeadPenetrationFeatherstone, ::testing::Values(0, 4),
                         [](const ::testing::TestParamInfo<int>& p) {
                           return p.param == 0 ? std::string("AllJoints") : std::string("Adaptive");
                         });

// A rebuild with the same head (a panel edit of friction) takes the grid already built; a cleared
// cache builds it again.
TEST(HeadCollisionsScene, ARebuildWithTheSameHeadReusesItsGrid) {
  Scene scene = loadScene("assets/scenes/ponytail.json");
  const auto gridOf = [](const Sim& sim) { return sim.collisions()->shapes().front().sdf.get(); };
  Sim a(scene, &assimpAssets());
  scene.collision->friction = 0.6;
  Sim b(scene, &assimpAssets());
  EXPECT_EQ(gridOf(a), gridOf(b));
  EXPECT_EQ(b.collisions()->params().friction, 0.6);
  clearHeadColliderCache();
  Sim c(scene, &assimpAssets());
  EXPECT_NE(gridOf(a), gridOf(c));
  scene.collision->cell = 0.004;  // another grid
  Sim d(scene, &assimpAssets());
  EXPECT_NE(gridOf(c), gridOf(d));
  EXPECT_EQ(gridOf(d)->cell(), 0.004);
}

// The optional joint limits of the collision section, through the scene: every joint's swing
// stays inside joint_cone and its twist inside joint_twist while the showcase throws the hair
// about. The rows act on velocities; what the integrator carries past the limit within a step is
// pushed back at the next contact stage: measured 0.21 deg of swing, 0.007 deg of twist.
TEST(HeadCollisionsScene, JointConesAndTwistLimitsHold) {
  Scene scene = loadScene("assets/scenes/ponytail.json");
  ASSERT_TRUE(scene.collision);
  scene.collision->joint_cone = 25.0;
  scene.collision->joint_twist = 10.0;
  Sim sim(scene, &assimpAssets());
  ASSERT_TRUE(sim.collisions());
  const Chain& chain = *sim.chain();
  std::vector<Eigen::Quaterniond> rest;
  for (size_t i = 1; i < chain.links.size(); ++i)
    rest.push_back(sim.world().body(chain.links[i - 1]).q.conjugate() * sim.world().body(chain.links[i]).q);
  const double deg = M_PI / 180.0;
  double swing = 0.0, twist = 0.0;
  for (int f = 1; f <= 120 && sim.ok(); ++f) {
    sim.advanceTo(f / 30.0);
    for (size_t i = 1; i < chain.links.size(); ++i) {
      const RigidBody& p = sim.world().body(chain.links[i - 1]);
      const RigidBody& c = sim.world().body(chain.links[i]);
      const Vector3d zp = p.q * Vector3d::UnitZ(), zc = c.q * Vector3d::UnitZ();
      swing = std::max(swing, std::atan2(zp.cross(zc).norm(), zp.dot(zc)));
      const Eigen::Quaterniond dev = (p.q * rest[i - 1]).conjugate() * c.q;
      twist = std::max(twist, std::abs(2.0 * std::atan2(dev.vec().z(), dev.w())));
    }
  }
  ASSERT_TRUE(sim.ok()) << sim.status();
  std::printf("joint swing at most %.4f deg (limit 25), twist at most %.4f deg (limit 10)\n", swing / deg, twist / deg);
  EXPECT_LT(swing, 25.5 * deg);
  EXPECT_LT(twist, 10.5 * deg);
  EXPECT_GT(swing, 20.0 * deg) << "the showcase does bend the joints to their limit";
  EXPECT_GT(twist, 8.0 * deg) << "the showcase does twist the joints to their limit";
}

// collision.self: links two or more apart do not pass through each other. The toss clip folds the
// ponytail onto itself on the head at about 2 s; the deepest overlap of two link capsules two or
// more apart over the first 2.2 s, with and without collision.self.
double selfOverlap(bool self) {
  Scene scene = loadScene("assets/scenes/ponytail_toss.json");
  EXPECT_TRUE(scene.collision);
  if (!scene.collision) return 0.0;
  scene.collision->self = self;
  Sim sim(scene, &assimpAssets());
  const Chain& chain = *sim.chain();
  double worst = 0.0;
  for (int f = 1; f <= 66 && sim.ok(); ++f) {
    sim.advanceTo(f / 30.0);
    const std::vector<CapsuleSegment> segs = chain.segments(sim.world());
    for (size_t i = 0; i < segs.size(); ++i)
      for (size_t j = i + 2; j < segs.size(); ++j)
        for (int a = 0; a <= 10; ++a)
          for (int b = 0; b <= 10; ++b) {
            const double s = a / 10.0, t = b / 10.0;
            const Vector3d p = segs[i].top + s * (segs[i].bottom - segs[i].top);
            const Vector3d q = segs[j].top + t * (segs[j].bottom - segs[j].top);
            const double ri = segs[i].radius_top + s * (segs[i].radius_bottom - segs[i].radius_top);
            const double rj = segs[j].radius_top + t * (segs[j].radius_bottom - segs[j].radius_top);
            worst = std::max(worst, ri + rj - (p - q).norm());
          }
  }
  EXPECT_TRUE(sim.ok()) << sim.status();
  std::printf("collision.self %s: deepest overlap of two links two or more apart %.3f mm\n", self ? "on" : "off",
              1e3 * worst);
  return worst;
}

TEST(HeadCollisionsScene, LinksTwoApartDoNotOverlap) { EXPECT_LT(selfOverlap(true), 1e-3); }

// The control: without collision.self the same clip does fold a link through another.
TEST(HeadCollisionsScene, WithoutSelfCollisionTheTossFoldsALinkThroughAnother) { EXPECT_GT(selfOverlap(false), 2e-3); }

// Two chains on a still head: the ponytail, and a second chain from the crown laid out toward the
// face, which falls onto the forehead. Each chain's link capsules below its root (the deepest
// point inside the mesh's triangles, per chain) over 0.5 s, with the scene's collider or without.
struct TwoChains {
  std::vector<double> deepest;  // m, per chain
  std::vector<int> capsules;    // the collider's capsules on each chain's links
  std::vector<bool> touching;   // a link of the chain within 0.1 mm of the head at the end
};
TwoChains twoChainsOnTheHead(bool collide) {
  Scene scene = loadScene("assets/scenes/ponytail.json");
  scene.head->animation.clip = "";  // no keys: the head holds still
  if (!collide) scene.collision.reset();
  if (scene.collision) scene.collision->cell = 0.005;  // a coarser grid: a fifth of the build's time
  ChainListSection crown;
  static_cast<ChainSection&>(crown) = *scene.chain;
  crown.links = 5;
  crown.anchor = Vector3d(0.0, 0.115, -0.01);  // mesh coordinates: just above the crown
  crown.direction = Vector3d(0.0, -1.0, 0.0);  // toward the face, level
  scene.chains.push_back(crown);
  Sim sim(scene, &assimpAssets());
  TwoChains out{std::vector<double>(2, 0.0), std::vector<int>(2, 0), std::vector<bool>(2, false)};
  EXPECT_EQ(sim.chains().size(), 2u);
  if (sim.chains().size() != 2) return out;
  std::vector<Vector3d> v;
  for (const auto& p : sim.head()->mesh.positions) v.push_back(sim.head()->mesh_to_body * p.cast<double>());
  const TriangleDistance exact(v, sim.head()->mesh.indices, 0.01, 0.02);
  for (int f = 1; f <= 30 && sim.ok(); ++f) {
    sim.advanceTo(f / 60.0);
    const RigidBody& head = sim.world().body(sim.headBody());
    for (size_t k = 0; k < 2; ++k) {
      const std::vector<CapsuleSegment> segs = sim.chains()[k].segments(sim.world());
      for (size_t i = 1; i < segs.size(); ++i)
        for (int j = 0; j <= 10; ++j) {
          const double s = j / 10.0;
          const Vector3d p = head.q.conjugate() * (segs[i].top + s * (segs[i].bottom - segs[i].top) - head.x);
          const double r = segs[i].radius_top + s * (segs[i].radius_bottom - segs[i].radius_top);
          out.deepest[k] = std::max(out.deepest[k], r - exact.signedDistance(p));
        }
    }
  }
  EXPECT_TRUE(sim.ok()) << sim.status();
  if (const Collisions* col = sim.collisions()) {
    for (size_t k = 0; k < 2; ++k) {
      const std::vector<int>& links = sim.chains()[k].links;
      const auto mine = [&links](int body) { return std::find(links.begin(), links.end(), body) != links.end(); };
      for (size_t i = 0; i < col->shapes().size(); ++i) out.capsules[k] += mine(col->shapeBody(int(i)));
      for (const Collisions::Row& r : col->detect(sim.world().bodies(), 1e-4))
        if (!r.angular && r.b == sim.headBody() && mine(r.a)) out.touching[k] = true;
    }
  }
  return out;
}

// Issue 34: a two-chain scene's chains collide with the head independently: each has its own
// capsules (every link but the root, held by its own cone), the crown chain lands on the forehead
// and is held off it (as the ponytail is), and without the collider it goes into the head.
TEST(HeadCollisionsScene, TwoChainsCollideWithTheHeadIndependently) {
  const TwoChains with = twoChainsOnTheHead(true);
  std::printf("two chains: deepest %.3f mm (ponytail), %.3f mm (crown chain)\n", 1e3 * with.deepest[0],
              1e3 * with.deepest[1]);
  EXPECT_EQ(with.capsules[0], 9);
  EXPECT_EQ(with.capsules[1], 4);
  EXPECT_TRUE(with.touching[1]) << "the crown chain lies on the forehead";
  EXPECT_LT(with.deepest[0], 1e-3);
  EXPECT_LT(with.deepest[1], 1e-3);
  const TwoChains without = twoChainsOnTheHead(false);
  std::printf("without the collider: crown chain %.1f mm deep\n", 1e3 * without.deepest[1]);
  EXPECT_GT(without.deepest[1], 5e-3) << "the control: the crown chain does fall into the head";
}

// The deepest point of any link capsule but the first inside the head's triangles (m, negative:
// the smallest clearance), in the head's body frame.
double deepestLink(const Sim& sim, const TriangleDistance& exact) {
  const RigidBody& head = sim.world().body(sim.headBody());
  const std::vector<CapsuleSegment> segs = sim.chain()->segments(sim.world());
  double deepest = -1e9;
  for (size_t i = 1; i < segs.size(); ++i)
    for (int k = 0; k <= 40; ++k) {
      const double s = k / 40.0;
      const Vector3d p = head.q.conjugate() * (segs[i].top + s * (segs[i].bottom - segs[i].top) - head.x);
      deepest = std::max(
          deepest, segs[i].radius_top + s * (segs[i].radius_bottom - segs[i].radius_top) - exact.signedDistance(p));
    }
  return deepest;
}

// Issue 36: the straight ponytail of t = 0 ran 10 mm into the skull on ponytail.json and
// ponytail_toss.json (the same head, chain and t = 0 pose), and the first step pushed it out
// (frame 0 showed the hair in the head, the next frame popped). The scene's initial pose is
// cleared before t = 0: measured against the triangles, no link but the first is inside the head
// (measured: 0.98 mm clear). With the head held still (so that the head's own turn does not move
// the links), the first step moves no link by more than gravity does (measured 0.03 mm; the pop
// was a jump of 11 mm in one 4 ms step).
// The head's own triangles in its body frame, for the exact distance.
TriangleDistance exactHead(const Sim& sim) {
  std::vector<Vector3d> v;
  for (const auto& p : sim.head()->mesh.positions) v.push_back(sim.head()->mesh_to_body * p.cast<double>());
  return TriangleDistance(v, sim.head()->mesh.indices, 0.01, 0.016);
}
std::vector<Vector3d> linkCentres(const Sim& sim) {
  std::vector<Vector3d> x;
  for (int id : sim.chain()->links) x.push_back(sim.world().body(id).x);
  return x;
}
// How far any link's centre has moved from `before` (m).
double largestJump(const Sim& sim, const std::vector<Vector3d>& before) {
  const std::vector<Vector3d> now = linkCentres(sim);
  double jump = 0.0;
  for (size_t i = 0; i < before.size(); ++i) jump = std::max(jump, (now[i] - before[i]).norm());
  return jump;
}

TEST(CleanFirstFrame, NoLinkStartsInTheHeadAndNothingPops) {
  std::optional<TriangleDistance> exact;
  for (const bool still : {false, true}) {
    std::vector<Override> set;
    if (still) set.push_back({"head.animation.clip", ""});
    Sim sim(loadScene("assets/scenes/ponytail.json", set), &assimpAssets());
    ASSERT_TRUE(sim.ok() && sim.head() && sim.chain() && sim.collisions());
    if (!exact) exact.emplace(exactHead(sim));
    const double start = deepestLink(sim, *exact);
    EXPECT_LT(start, 0.0) << "a link but the first starts inside the head";
    const std::vector<Vector3d> before = linkCentres(sim);
    ASSERT_TRUE(sim.step()) << sim.status();
    const double jump = largestJump(sim, before);
    std::printf(
        "ponytail%s: at t = 0 the deepest link point is %.3f mm inside (negative: clear), the first step "
        "moves a link %.3f mm\n",
        still ? " (head still)" : "", 1e3 * start, 1e3 * jump);
    if (still) {
      EXPECT_LT(jump, 5e-4) << "the first step pops a link";
    }
  }
}

// The same on long_hair.json (64 links laid out from the crown, featherstone, adaptive dynamics):
// the laid-out line runs into the back of the head and the pose is cleared before t = 0, so no link
// but the first starts inside (the draft of 16 mm links on 4.5 mm joints, thicker than the links
// are long, could not be cleared and started 26 mm deep); with the head still, the first steps move
// no link by more than gravity does.
TEST(CleanFirstFrame, LongHairStartsOutsideTheHead) {
  Sim sim(loadScene("assets/scenes/long_hair.json", {{"head.animation.clip", ""}}), &assimpAssets());
  ASSERT_TRUE(sim.ok() && sim.head() && sim.chain() && sim.collisions()) << sim.status();
  ASSERT_EQ(sim.chain()->links.size(), 64u);
  const double start = deepestLink(sim, exactHead(sim));
  const std::vector<Vector3d> before = linkCentres(sim);
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(sim.step()) << sim.status();
  const double jump = largestJump(sim, before);
  std::printf(
      "long_hair: at t = 0 the deepest link point is %.3f mm inside (negative: clear); 3 steps move a "
      "link %.3f mm\n",
      1e3 * start, 1e3 * jump);
  EXPECT_LT(start, 0.0) << "a link but the first starts inside the head";
  EXPECT_LT(jump, 1e-3) << "the first steps pop a link";
}

INSTANTIATE_TEST_SUITE_P(Meshes, HeadPenetration, ::testing::Values("default", "sphere", "box"));

}  // namespace
}  // namespace ponyhop

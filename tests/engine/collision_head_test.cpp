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
#include <unordered_map>

#include "engine/asset_loader.h"
#include "engine/mesh.h"
#include "sim/scene_io.h"
#include "sim/sim.h"
#include "physics/head_collisions.h"
#include "physics/mesh_sdf.h"
#include "physics/shapes.h"

namespace ponyhop {
namespace {

using Eigen::Vector3d;

void writeObj(const MeshData& m, const std::string& path) {
  std::ofstream f(path);
  for (const auto& p : m.positions) f << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (size_t i = 0; i < m.indices.size(); i += 3)
    f << "f " << m.indices[i] + 1 << ' ' << m.indices[i + 1] + 1 << ' ' << m.indices[i + 2] + 1 << '\n';
}

// Exact signed distance to the triangles: the distance over the triangles in nearby buckets
// (a uniform grid), the sign by ray parity (majority of +x, +y, +z) over all triangles.
class TriangleDistance {
 public:
  TriangleDistance(std::vector<Vector3d> v, std::vector<uint32_t> idx, double bucket)
      : v_(std::move(v)), idx_(std::move(idx)), bucket_(bucket) {
    for (size_t t = 0; t < idx_.size() / 3; ++t) {
      const Vector3d c = (v_[idx_[3 * t]] + v_[idx_[3 * t + 1]] + v_[idx_[3 * t + 2]]) / 3.0;
      double reach = 0.0;
      for (int k = 0; k < 3; ++k) reach = std::max(reach, (v_[idx_[3 * t + k]] - c).norm());
      max_reach_ = std::max(max_reach_, reach);
      buckets_[key(c)].push_back(static_cast<int>(t));
    }
  }
  // Exact |distance| when it is below `within` (else a value >= within), with the parity sign.
  double signedDistance(const Vector3d& p, double within) const {
    const int span = static_cast<int>(std::ceil((within + max_reach_) / bucket_));
    const Eigen::Vector3i c = cellOf(p);
    double best = within;
    for (int dz = -span; dz <= span; ++dz)
      for (int dy = -span; dy <= span; ++dy)
        for (int dx = -span; dx <= span; ++dx) {
          const auto it = buckets_.find(key(Eigen::Vector3i(c + Eigen::Vector3i(dx, dy, dz))));
          if (it == buckets_.end()) continue;
          for (int t : it->second)
            best = std::min(best, (p - closestPointOnTriangle(p, v_[idx_[3 * t]], v_[idx_[3 * t + 1]], v_[idx_[3 * t + 2]])).norm());
        }
    if (best >= within) return best;
    return ponyhop::signedDistanceToTriangles(v_, idx_, p) < 0.0 ? -best : best;
  }

 private:
  Eigen::Vector3i cellOf(const Vector3d& p) const { return (p / bucket_).array().floor().cast<int>(); }
  long long key(const Vector3d& p) const { return key(cellOf(p)); }
  static long long key(const Eigen::Vector3i& c) {
    return ((static_cast<long long>(c.x()) + 100000) * 200000 + (c.y() + 100000)) * 200000 + (c.z() + 100000);
  }
  std::vector<Vector3d> v_;
  std::vector<uint32_t> idx_;
  double bucket_;
  double max_reach_ = 0.0;
  std::unordered_map<long long, std::vector<int>> buckets_;
};

struct Result {
  double deepest = 0.0;  // m, deepest point of any link capsule (1..n-1) inside the mesh
  int frame = -1;
  int contacts_max = 0;
  double seconds = 0.0;  // wall time of the simulation with collisions
};

Result play(const std::string& mesh_path, const std::string& clip, double duration, bool collide = true) {
  Scene scene = loadScene("assets/scenes/ponytail.json");
  if (!mesh_path.empty()) {
    scene.head->mesh = mesh_path;
    scene.head->anchor_space = AnchorSpace::Bounds;  // the anchor: found on the mesh's surface
  }
  scene.head->animation.clip = clip;
  Sim rt(scene, &assimpAssets());
  EXPECT_TRUE(rt.ok()) << rt.status();
  EXPECT_TRUE(rt.head() && rt.chain());
  if (!rt.head() || !rt.chain()) return {};
  const MeshData& mesh = rt.head()->mesh;
  const Eigen::Affine3d T = rt.head()->mesh_to_body;
  std::vector<Vector3d> v;
  for (const auto& p : mesh.positions) v.push_back(T * p.cast<double>());
  HeadCollisionParams hp;
  std::string err;
  auto col = makeHeadCollisions(rt.world(), *rt.chain(), rt.headBody(), v, mesh.indices, hp, &err);
  EXPECT_TRUE(col) << err;
  if (!col) return {};
  if (collide) col->attach(rt.world());
  TriangleDistance exact(v, mesh.indices, 0.01);
  Result res;
  const Chain& chain = *rt.chain();
  const int frames = static_cast<int>(duration * 30.0);
  for (int f = 1; f <= frames && rt.ok(); ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    rt.advanceTo(f / 30.0);
    res.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    res.contacts_max = std::max(res.contacts_max, col->stats().active);
    const RigidBody& head = rt.world().body(rt.headBody());
    const std::vector<CapsuleSegment> segs = chain.segments(rt.world());
    for (size_t i = 1; i < segs.size(); ++i) {
      for (int k = 0; k <= 20; ++k) {
        const double s = k / 20.0;
        const Vector3d p_world = segs[i].top + s * (segs[i].bottom - segs[i].top);
        const double r = segs[i].radius_top + s * (segs[i].radius_bottom - segs[i].radius_top);
        const Vector3d p = head.q.conjugate() * (p_world - head.x);  // head body frame
        const double d = exact.signedDistance(p, r + 0.005);
        if (r - d > res.deepest) {
          res.deepest = r - d;
          res.frame = f;
        }
      }
    }
  }
  EXPECT_TRUE(rt.ok()) << rt.status();
  return res;
}

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
    const Result r = play(path, clip, 10.0);
    std::printf("%s / %s: deepest %.3f mm (frame %d), contacts max %d, %.2f s wall for 10 s\n", which.c_str(), clip,
                1e3 * r.deepest, r.frame, r.contacts_max, r.seconds);
    EXPECT_LT(r.deepest, 1e-3) << which << " " << clip << " frame " << r.frame;
    EXPECT_GT(r.contacts_max, 0) << "the clip never brings the hair onto the head: the test shows nothing";
  }
}

// The control: the same measurement without the collider finds the hair inside the head (the
// measurement can fail; the clips do throw the ponytail into the skull).
TEST(HeadPenetrationControl, WithoutTheColliderTheShowcaseGoesThroughTheHead) {
  const Result r = play("", "showcase", 10.0, false);
  std::printf("default / showcase without the collider: deepest %.1f mm (frame %d), %.2f s wall for 10 s\n",
              1e3 * r.deepest, r.frame, r.seconds);
  EXPECT_GT(r.deepest, 5e-3);
}

INSTANTIATE_TEST_SUITE_P(Meshes, HeadPenetration, ::testing::Values("default", "sphere", "box"));

}  // namespace
}  // namespace ponyhop

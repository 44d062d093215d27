// `ponyhop export`: the glTF bake read back through assimp, every node's pose at every frame
// against the simulation stepped independently (frame times that fall on physics steps).
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <map>
#include <set>

#include "app/pose_sampling.h"
#include "common/run_util.h"
#include "engine/asset_loader.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

using testing::runPonyhop;
using testing::scratch;

const aiNode* findNode(const aiNode* n, const std::string& name) {
  if (name == n->mName.C_Str()) return n;
  for (unsigned i = 0; i < n->mNumChildren; ++i)
    if (const aiNode* f = findNode(n->mChildren[i], name)) return f;
  return nullptr;
}

struct RoundTrip {
  double max_position = 0.0;  // m
  double max_angle = 0.0;     // rad
  int frames = 0;
  int nodes = 0;
};

RoundTrip roundTrip(const std::string& scene_path, double fps, int frames) {
  RoundTrip rt_err;
  const std::string tag = "gltf_export_" + std::filesystem::path(scene_path).stem().string();
  const std::string dir = scratch(tag);
  const std::string glb = dir + "/motion.glb";
  const auto r = runPonyhop("export " + scene_path + " --out " + glb + " --fps " + std::to_string(fps) + " --frames " +
                                std::to_string(frames),
                            tag);
  EXPECT_EQ(r.code, 0) << r.out;
  Assimp::Importer importer;
  const aiScene* s = importer.ReadFile(glb, aiProcess_ValidateDataStructure);
  EXPECT_NE(s, nullptr) << importer.GetErrorString();
  if (!s) return rt_err;
  EXPECT_EQ(s->mNumAnimations, 1u);
  if (s->mNumAnimations != 1) return rt_err;
  const aiAnimation* anim = s->mAnimations[0];
  const double tps = anim->mTicksPerSecond > 0 ? anim->mTicksPerSecond : 1.0;

  Sim sim(loadScene(scene_path), &assimpAssets());
  const std::vector<std::string> ids = bodyIds(sim.world());
  std::map<std::string, const aiNodeAnim*> channels;
  for (unsigned c = 0; c < anim->mNumChannels; ++c)
    channels[anim->mChannels[c]->mNodeName.C_Str()] = anim->mChannels[c];
  rt_err.nodes = int(ids.size());
  for (const std::string& id : ids) {
    const aiNode* node = findNode(s->mRootNode, id);
    EXPECT_NE(node, nullptr) << id;
    if (node) {
      EXPECT_EQ(node->mNumMeshes, 1u) << id << " carries its mesh";
    }
    EXPECT_TRUE(channels.count(id)) << id << " is animated";
    if (channels.count(id)) {
      EXPECT_EQ(channels[id]->mNumPositionKeys, unsigned(frames)) << id;
      EXPECT_EQ(channels[id]->mNumRotationKeys, unsigned(frames)) << id;
    }
  }
  // The root turns z up into y up: world +z is the file's +y.
  const aiNode* root = findNode(s->mRootNode, "ponyhop");
  EXPECT_NE(root, nullptr);
  if (root) {
    const aiVector3D z = aiMatrix3x3(root->mTransformation) * aiVector3D(0, 0, 1);
    EXPECT_NEAR(z.y, 1.0, 1e-6);
  }
  for (int k = 0; k < frames; ++k) {
    const double t = k / fps;
    EXPECT_TRUE(sim.advanceTo(t));
    EXPECT_NEAR(sim.time(), t, 1e-9) << "frame times must fall on steps for this test";
    for (int i = 0; i < sim.world().bodyCount(); ++i) {
      const auto it = channels.find(ids[size_t(i)]);
      if (it == channels.end() || unsigned(k) >= it->second->mNumPositionKeys) continue;
      const aiVectorKey& pk = it->second->mPositionKeys[k];
      const aiQuatKey& qk = it->second->mRotationKeys[k];
      EXPECT_NEAR(pk.mTime / tps, t, 1e-6);
      EXPECT_NEAR(qk.mTime / tps, t, 1e-6);
      const RigidBody& b = sim.world().body(i);
      const Eigen::Vector3d p(pk.mValue.x, pk.mValue.y, pk.mValue.z);
      const Eigen::Quaterniond q(qk.mValue.w, qk.mValue.x, qk.mValue.y, qk.mValue.z);
      rt_err.max_position = std::max(rt_err.max_position, (p - b.x).norm());
      rt_err.max_angle = std::max(rt_err.max_angle, q.normalized().angularDistance(b.q));
    }
  }
  rt_err.frames = frames;
  return rt_err;
}

TEST(GltfExport, HeadAndPonytailRoundTripThroughAssimp) {
  const RoundTrip e = roundTrip("assets/scenes/ponytail.json", 30.0, 60);  // dt 1/240: 8 steps a frame
  std::printf("ponytail: %d nodes x %d frames, max error %.3g m, %.3g rad\n", e.nodes, e.frames, e.max_position,
              e.max_angle);
  EXPECT_EQ(e.frames, 60);
  EXPECT_LT(e.max_position, 1e-5);
  EXPECT_LT(e.max_angle, 1e-5);
}

TEST(GltfExport, HopperWithItsPonytailRoundTripsThroughAssimp) {
  const RoundTrip e = roundTrip("assets/scenes/ponytail_hopper.json", 50.0, 50);  // dt 1 ms: 20 steps a frame
  std::printf("ponytail_hopper: %d nodes x %d frames, max error %.3g m, %.3g rad\n", e.nodes, e.frames, e.max_position,
              e.max_angle);
  EXPECT_EQ(e.frames, 50);
  EXPECT_LT(e.max_position, 1e-5);
  EXPECT_LT(e.max_angle, 1e-5);
}

TEST(GltfExport, TwoChainsOnTheHeadRoundTripThroughAssimp) {
  // pigtails.json: two chains, no `chain`: each chain's links are their own animated nodes.
  const RoundTrip e = roundTrip("assets/scenes/pigtails.json", 30.0, 15);  // dt 1/240: 8 steps a frame
  std::printf("pigtails: %d nodes x %d frames, max error %.3g m, %.3g rad\n", e.nodes, e.frames, e.max_position,
              e.max_angle);
  EXPECT_EQ(e.frames, 15);
  Sim sim(loadScene("assets/scenes/pigtails.json"), &assimpAssets());
  ASSERT_EQ(sim.chains().size(), 2u);
  size_t links = 0;
  for (const Chain& c : sim.chains()) links += c.links.size();
  EXPECT_GE(size_t(e.nodes), links + 1) << "every link of both chains, and the head, is a node";
  // The two chains are different bodies with different names: no node was written twice.
  const std::vector<std::string> ids = bodyIds(sim.world());
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), ids.size());
  EXPECT_LT(e.max_position, 1e-5);
  EXPECT_LT(e.max_angle, 1e-5);
}

TEST(GltfExport, RefusesAnOutputThatIsNotGlb) {
  const std::string dir = scratch("gltf_export_bad");
  const auto r = runPonyhop("export assets/scenes/chain.json --out " + dir + "/motion.fbx", "gltf_export_bad");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find(".glb"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "/motion.fbx"));
}

}  // namespace
}  // namespace ponyhop

// Heads nobody here made (Debian's assimp-testmodels, installed by scripts/setup.sh) land well:
// four of them pass every check below (the duck does not, see kHeads).
// the head (not a whole body) is head.height tall, the ponytail's anchor is on the back half of
// the head, and at t = 0 the ponytail touches nothing but its anchor. Textures are drawn, and an
// unreadable one is named in a warning.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/run_util.h"
#include "engine/asset_loader.h"
#include "engine/frame_writer.h"
#include "engine/mesh.h"
#include "physics/shapes.h"
#include "sim/head_fit.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
using testing::runPonyhop;
using testing::scratch;

const std::string kModels = "/usr/share/assimp/models/";

struct HeadCase {
  const char* name;
  const char* path;  // under kModels
};
// What gtest prints for a case, in its output and in the ctest names gtest_discover_tests makes
// ("... # GetParam() = mrfixit"): the name, not the struct's bytes (two pointers that change with
// every build).
void PrintTo(const HeadCase& c, std::ostream* os) { *os << c.name; }

const HeadCase kHeads[] = {
    {"mrfixit", "IQM/mrfixit.iqm"},          // a whole body, z up, two textures
    {"suzanne", "BLEND/Suzanne_248.blend"},  // Blender's monkey, z up
    {"wuson", "OBJ/WusonOBJ.obj"},           // up axis from the shape
    // Not the Collada duck: a whole bird whose tail is the "back of the head"; with the anchor
    // 60 % up its back, the straight ponytail of t = 0 touches the tail (at 75 % it clears the
    // duck but cuts through round skulls like Suzanne's). Left out, named in docs/HEADS.md.
    {"sydney", "MD2/sydney.md2"},          // a whole body, one hand raised to the head, textured
    {"human_blend", "BLEND/HUMAN.blend"},  // a bust, z up, centred
    {"human_dae", "Collada/human.zae"},    // a whole body, y up, standing on the origin
};

std::vector<Override> headOverrides(const std::string& mesh) {
  return {{"head.mesh", mesh}, {"head.anchor_space", "bounds"}, {"head.animation.clip", ""}};
}

class Heads : public ::testing::TestWithParam<HeadCase> {};

TEST_P(Heads, LandWellWithThePonytailOnTheBackOfTheHead) {
  const HeadCase& c = GetParam();
  const std::string mesh = kModels + c.path;
  ASSERT_TRUE(fs::exists(mesh)) << mesh << " is missing: scripts/setup.sh installs assimp-testmodels";
  const Scene scene = loadScene("assets/scenes/ponytail.json", headOverrides(mesh));
  Sim sim(scene, &assimpAssets());
  const HeadFit fit = fitHead(*scene.head, mesh, sim.head()->mesh);
  const RigidBody& head = sim.world().body(sim.headBody());

  // The head's part, in the world at t = 0.
  Eigen::AlignedBox3d box;
  std::vector<Eigen::Vector3d> all_points;
  for (const auto& p : sim.head()->mesh.positions) {
    const Eigen::Vector3d w = head.pointToWorld(sim.head()->mesh_to_body * p.cast<double>());
    all_points.push_back(w);
    if (fit.head_bounds.contains(p)) {
      box.extend(head.q.conjugate() * (w - head.x));  // body frame
    }
  }
  std::printf("%s: up %s (%s), %s, head %.3f m tall, pivot (%.3g %.3g %.3g)\n", c.name, fit.up == UpAxis::Z ? "z" : "y",
              fit.up_reason.c_str(), fit.whole_body ? "whole body" : "a head", box.sizes().z(), fit.pivot.x(),
              fit.pivot.y(), fit.pivot.z());
  EXPECT_NEAR(box.sizes().z(), scene.head->height, 0.01 * scene.head->height) << "the head is head.height tall";
  // Recentred: the head's bounds hold the body origin (the pivot of its keyframes).
  EXPECT_TRUE(box.contains(Eigen::Vector3d::Zero())) << "the head's bounds hold its pivot";

  // The anchor: on the back half (body +y is the back), high on the head, on or near its surface.
  const Chain* chain = sim.chain();
  ASSERT_NE(chain, nullptr);
  const Eigen::Vector3d anchor = chain->anchor_local;
  EXPECT_GT(anchor.y(), box.center().y()) << "the anchor is on the back half";
  EXPECT_GT(anchor.z(), box.center().z()) << "the anchor is on the upper half";
  // Nearest point of the head's own triangles (a low-poly head's vertices lie far apart).
  double nearest = 1e9;
  const auto& mesh_data = sim.head()->mesh;
  const Eigen::Vector3d anchor_world = head.pointToWorld(anchor);
  for (size_t t = 0; t + 2 < mesh_data.indices.size(); t += 3) {
    Eigen::Vector3d v[3];
    bool in_head = true;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3f& p = mesh_data.positions[mesh_data.indices[t + size_t(k)]];
      in_head = in_head && fit.head_bounds.contains(p);
      v[k] = head.pointToWorld(sim.head()->mesh_to_body * p.cast<double>());
    }
    if (in_head)
      nearest = std::min(nearest, (closestPointOnTriangle(anchor_world, v[0], v[1], v[2]) - anchor_world).norm());
  }
  EXPECT_LT(nearest, chain->radii.front() + 0.005) << "the first link holds on to the head";

  // At t = 0 no link but the first touches the mesh (the whole mesh: a body's back too).
  const auto segs = chain->segments(sim.world());
  int touching = 0;
  for (size_t i = 1; i < segs.size(); ++i) {
    const Eigen::Vector3d a = segs[i].top, d = segs[i].bottom - segs[i].top;
    for (const auto& p : all_points) {
      const double s = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      if ((p - (a + s * d)).norm() < std::max(segs[i].radius_top, segs[i].radius_bottom) - 1e-4) {
        ++touching;
        break;
      }
    }
  }
  EXPECT_EQ(touching, 0) << "links touching the head at t = 0";
}

// The same heads given to the demo scene the way a user would (`--set head.mesh=...` alone: the
// anchor comes from the head's bounds) swing the showcase clip with the head collider on.
TEST_P(Heads, SwingTheShowcaseWithTheCollider) {
  const std::string mesh = kModels + GetParam().path;
  ASSERT_TRUE(fs::exists(mesh)) << mesh << " is missing: scripts/setup.sh installs assimp-testmodels";
  const Scene scene = loadScene("assets/scenes/ponytail.json", {{"head.mesh", mesh}});
  ASSERT_EQ(scene.head->anchor_space, AnchorSpace::Bounds);
  Sim sim(scene, &assimpAssets());
  ASSERT_NE(sim.collisions(), nullptr);
  while (sim.ok() && sim.time() < 3.0) sim.step();
  EXPECT_TRUE(sim.ok()) << sim.status();
}

INSTANTIATE_TEST_SUITE_P(ThirdParty, Heads, ::testing::ValuesIn(kHeads),
                         [](const ::testing::TestParamInfo<HeadCase>& i) { return std::string(i.param.name); });

// The default head stays where it was: its mesh origin (the skull's centre) is the pivot.
TEST(HeadsDefault, DefaultHeadKeepsItsPlacement) {
  const Scene scene = loadScene("assets/scenes/ponytail.json");
  Sim sim(scene, &assimpAssets());
  const HeadFit fit = fitHead(*scene.head, "assets/head/head.gltf", sim.head()->mesh);
  EXPECT_EQ(fit.up, UpAxis::Y);
  EXPECT_FALSE(fit.whole_body);
  EXPECT_TRUE(fit.pivot.isZero(0.0));
  EXPECT_TRUE(sim.head()->mesh_to_body.isApprox(meshToBody(*scene.head, sim.head()->mesh.bbox), 0.0));
}

// A textured cube: its faces show the texture (the render with the file's materials has colours
// the plain one lacks), and a missing texture is named.
TEST(HeadsTexture, TexturedCubeShowsItsTextureAndAMissingOneIsNamed) {
  const std::string mesh = kModels + "glTF2/BoxTextured-glTF/BoxTextured.gltf";
  ASSERT_TRUE(fs::exists(mesh)) << mesh << " is missing: scripts/setup.sh installs assimp-testmodels";
  const std::string dir = scratch("heads_texture");
  const std::string common = "render assets/scenes/head.json --frames 1 --size 128x96 --set head.mesh=" + mesh;
  const auto tex = runPonyhop(common + " --out " + dir + "/tex", "heads_texture");
  ASSERT_EQ(tex.code, 0) << tex.out;
  const auto plain = runPonyhop(common + " --set head.materials=color --out " + dir + "/plain", "heads_plain");
  ASSERT_EQ(plain.code, 0) << plain.out;
  std::string err;
  const auto a = readPng(FrameWriter::framePath(dir + "/tex", 0), &err);
  const auto b = readPng(FrameWriter::framePath(dir + "/plain", 0), &err);
  ASSERT_TRUE(a && b) << err;
  // Saturated pixels: the texture's colours against the skin colour.
  const auto saturated = [](const Image& img) {
    int n = 0;
    for (size_t i = 0; i + 3 < img.rgba.size(); i += 4) {
      const int mx = std::max({img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]});
      const int mn = std::min({img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]});
      n += (mx - mn) > 60;
    }
    return n;
  };
  std::printf("saturated pixels: textured %d, plain %d\n", saturated(*a), saturated(*b));
  EXPECT_GT(saturated(*a), saturated(*b) + 200);

  // The same cube with its texture file missing: drawn, and the warning names the file.
  const std::string copy = dir + "/missing";
  fs::create_directories(copy);
  fs::copy_file(mesh, copy + "/BoxTextured.gltf");
  fs::copy_file(kModels + "glTF2/BoxTextured-glTF/BoxTextured0.bin", copy + "/BoxTextured0.bin");
  const auto missing = runPonyhop("render assets/scenes/head.json --frames 1 --size 64x48 --set head.mesh=" + copy +
                                      "/BoxTextured.gltf --out " + dir + "/m",
                                  "heads_missing");
  EXPECT_EQ(missing.code, 0) << missing.out;
  EXPECT_NE(missing.out.find("warning"), std::string::npos) << missing.out;
  EXPECT_NE(missing.out.find("CesiumLogoFlat.png"), std::string::npos) << missing.out;
}

// A model that names no skin (Quake II MD2: assimp puts its placeholder "$texture_dummy.bmp" in
// the material) takes the image beside it under its name, and says nothing when there is none; a
// texture a file names but that is not there is named once, plainly, however often the head loads.
TEST(HeadsTexture, AnUnnamedSkinIsFoundBesideTheModelAndAMissingNamedOneIsSaidOnce) {
  const std::string sydney = kModels + "MD2/sydney.md2";
  const std::string dwarf = kModels + "COB/dwarf.cob";
  ASSERT_TRUE(fs::exists(sydney) && fs::exists(dwarf)) << "scripts/setup.sh installs assimp-testmodels";
  MeshData m;
  std::string err;
  ASSERT_TRUE(loadMesh(sydney, m, &err)) << err;
  EXPECT_EQ(m.textures.size(), 1u) << "sydney.bmp, beside sydney.md2";
  EXPECT_TRUE(m.warnings.empty()) << m.warnings.front();

  const std::string lone = scratch("heads_lone_md2");
  fs::copy_file(sydney, lone + "/sydney.md2", fs::copy_options::overwrite_existing);
  MeshData bare;
  ASSERT_TRUE(loadMesh(lone + "/sydney.md2", bare, &err)) << err;
  EXPECT_TRUE(bare.textures.empty());
  EXPECT_TRUE(bare.warnings.empty()) << "no texture named, none beside: nothing to say, not " << bare.warnings.front();

  HeadParams head;
  head.anchor_space = AnchorSpace::Bounds;
  ::testing::internal::CaptureStderr();
  assimpAssets().loadHead(head, dwarf, "dwarf.json");
  assimpAssets().loadHead(head, dwarf, "dwarf.json");
  const std::string said = ::testing::internal::GetCapturedStderr();
  std::printf("%s", said.c_str());
  for (const char* name : {"axe.jpg", "dwarf.jpg"}) {
    const std::string line = std::string("the texture ") + name + " that dwarf.cob names is not there";
    const size_t at = said.find(line);
    EXPECT_NE(at, std::string::npos) << said;
    EXPECT_EQ(said.find(line, at + 1), std::string::npos) << "said twice:\n" << said;
  }
}

// A skinned file is drawn in its skeleton's rest pose: DirectX's BCN_Epileptic.X (three meshes
// placed by their bones) comes out as the same man as its XGL copy, the same proportions along
// his three axes. By the meshes' nodes alone his head, torso and legs came apart.
TEST(HeadsLoad, ASkinnedCharacterIsDrawnInItsRestPose) {
  const auto proportions = [](const std::string& path) {
    MeshData m;
    std::string err;
    EXPECT_TRUE(loadMesh(path, m, &err)) << err;
    Eigen::Vector3f e = m.bbox.sizes();
    std::sort(e.data(), e.data() + 3);
    return Eigen::Vector3f(e / e.z());
  };
  const Eigen::Vector3f x = proportions(kModels + "X/BCN_Epileptic.X");
  const Eigen::Vector3f xgl = proportions(kModels + "XGL/BCN_Epileptic.zgl");
  EXPECT_LT((x - xgl).cwiseAbs().maxCoeff(), 0.02f) << x.transpose() << " against " << xgl.transpose();
}

// A file assimp reads without a mesh in it (Half-Life's manT.mdl: its textures only) is refused
// with a reason, not an empty one.
TEST(HeadsLoad, AFileWithoutAMeshSaysWhy) {
  const std::string textures = kModels + "MDL/MDL (HL1)/manT.mdl";
  ASSERT_TRUE(fs::exists(textures)) << "scripts/setup.sh installs assimp-testmodels";
  MeshData m;
  std::string err;
  EXPECT_FALSE(loadMesh(textures, m, &err));
  std::printf("%s\n", err.c_str());
  EXPECT_NE(err.find("assimp read no mesh from it"), std::string::npos) << err;
}

// A whole character the automatic fit cannot read says so, and tells how to pick the head by hand;
// the box given picks it (fit only: no simulation). The mesh: a wall 1.8 tall, 1 wide, 0.2 deep, z
// up: a whole body by its shape, with no neck from either end and no head-like top.
TEST(UnsureCharacters, SaySoAndTellHowToPickTheHeadByHand) {
  const std::string mesh = scratch("heads_unsure") + "/wall.obj";
  {
    std::ofstream obj(mesh);
    for (int k = 0; k < 8; ++k)
      obj << "v " << ((k & 1) ? 0.5 : -0.5) << ' ' << ((k & 2) ? 0.1 : -0.1) << ' ' << ((k & 4) ? 1.8 : 0.0) << '\n';
    obj << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  }
  MeshData m;
  std::string err;
  ASSERT_TRUE(loadMesh(mesh, m, &err)) << err;
  HeadParams head;
  const HeadFit fit = fitHead(head, mesh, m);
  EXPECT_TRUE(fit.whole_body);
  EXPECT_FALSE(fit.upside_down);
  ASSERT_FALSE(fit.unsure.empty());
  const std::string said = unsureFitMessage(fit, m);
  std::printf("%s\n", said.c_str());
  EXPECT_NE(said.find("--set head.box_min="), std::string::npos) << said;

  // By hand: the head is the vertices inside the box, and the fit is sure.
  head.box_min = m.bbox.min().cast<double>();
  head.box_max = m.bbox.center().cast<double>();
  const HeadFit hand = fitHead(head, mesh, m);
  EXPECT_TRUE(hand.by_hand);
  EXPECT_TRUE(hand.unsure.empty());
  Eigen::AlignedBox3f inside;
  for (const auto& p : m.positions)
    if ((p.array() >= m.bbox.min().array()).all() && (p.array() <= m.bbox.center().array()).all()) inside.extend(p);
  EXPECT_TRUE(hand.head_bounds.isApprox(inside));
}

// Whole characters beyond the heads above, fitted automatically (fit only, no simulation): the
// head found at the top of the body, upright, head.height tall, facing body -y, with the anchor on
// the back of the skull. `up` and `face` are the mesh's own directions, read off renders of each.
struct WholeCase {
  const char* name;
  const char* path;  // under kModels
  Eigen::Vector3d up, face;
  // How far above the head's centre the anchor must be, a fraction of the head's height (below 0: a
  // character whose own braid sticks out behind the skull, where the back of its bounds is nearest).
  double anchor_above = 0.0;
  // The head's largest share of the body's height (a person is 6 to 8 heads tall; a caricature less).
  double max_share = 0.25;
};
void PrintTo(const WholeCase& c, std::ostream* os) { *os << c.name; }
const WholeCase kWhole[] = {
    // Quake II: wings behind her, a stick above her head; looks along +x as Quake's models do.
    {"faerie", "MD2/faerie.md2", Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX()},
    // 3ds Max (ASE): a mannequin in a T pose, y up after import, looking along +z.
    {"mocap_rom", "ASE/MotionCaptureROM.ase", Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()},
    // DirectX, skinned: head, torso and legs are three meshes placed by their bones (the rest pose;
    // by their nodes alone they came out apart and head down), y up, looking along +z.
    // Its own braid hangs from the back of its skull: the anchor lands at the braid's root, at
    // mid-height (4 % of the head's height below its centre).
    {"bcn_epileptic", "X/BCN_Epileptic.X", Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), -0.1},
    // The same man as XGL, standing head up: the file says nothing, z up by its shape, and the
    // face along -y as z-up files are taken to look (his feet agree).
    {"bcn_epileptic_xgl", "XGL/BCN_Epileptic.zgl", Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitY(), -0.1},
    // A caricature dwarf (COB), z up, three heads tall under a horned helmet: the axe he holds out
    // along +y made the mesh as deep as tall (a whole body only without it), and he looks along
    // +y, against the z-up convention: his feet say so.
    {"dwarf", "COB/dwarf.cob", Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitY(), 0.0, 0.35},
    // IQM (the Quake family): y up after import, arms spread along z, looking along +x like Quake's
    // MD2 models (his feet say so; before, his ponytail hung from the side of his head).
    {"mrfixit", "IQM/mrfixit.iqm", Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX()},
};
class WholeCharacters : public ::testing::TestWithParam<WholeCase> {};

TEST_P(WholeCharacters, LandUprightWithThePonytailOnTheBackOfTheSkull) {
  const WholeCase& c = GetParam();
  const std::string mesh = kModels + c.path;
  ASSERT_TRUE(fs::exists(mesh)) << mesh << " is missing: scripts/setup.sh installs assimp-testmodels";
  MeshData m;
  std::string err;
  ASSERT_TRUE(loadMesh(mesh, m, &err)) << err;
  const Scene scene = loadScene("assets/scenes/ponytail.json", headOverrides(mesh));
  const HeadFit fit = fitHead(*scene.head, mesh, m);
  EXPECT_TRUE(fit.whole_body);
  EXPECT_EQ(fit.unsure, "");
  const Eigen::Matrix3d L = headMeshToBody(*scene.head, fit).linear();
  // Upright and facing body -y.
  EXPECT_GT((L * c.up).normalized().z(), 0.999) << "the mesh's up is the body's +z";
  EXPECT_LT((L * c.face).normalized().y(), -0.999) << "the face looks along the body's -y";
  // The head: at the top of the body (the far end along the mesh's up, which may point down its
  // axis), a head's share of its height, head.height tall.
  const Eigen::Vector3d lo = fit.head_bounds.min().cast<double>(), hi = fit.head_bounds.max().cast<double>();
  const Eigen::Vector3d all_lo = m.bbox.min().cast<double>(), all_hi = m.bbox.max().cast<double>();
  const Eigen::Vector3d extent_axis = c.up.cwiseAbs();
  const double body = extent_axis.dot(all_hi - all_lo), head = extent_axis.dot(hi - lo);
  const auto top_along = [&c](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::max(c.up.dot(a), c.up.dot(b));
  };
  const double below = top_along(all_lo, all_hi) - top_along(lo, hi);
  std::printf("%s: head %.3g of the body's height, its top %.3g below the mesh's\n", c.name, head / body, below / body);
  EXPECT_LT(below, 0.1 * body) << "the head is at the top";
  EXPECT_GT(head, 0.08 * body);
  EXPECT_LT(head, c.max_share * body);
  EXPECT_NEAR(std::abs((L * (hi - lo)).z()), scene.head->height, 1e-6) << "head.height tall";
  // The anchor: behind the head's centre (away from the face) and above it.
  const Eigen::Vector3d anchor = headAnchorInMesh(*scene.head, fit, m), centre = 0.5 * (lo + hi);
  EXPECT_LT((anchor - centre).dot(c.face), 0.0) << "the anchor is on the back of the skull";
  EXPECT_GT((anchor - centre).dot(c.up), c.anchor_above * head) << "the anchor is on the upper half";
}

INSTANTIATE_TEST_SUITE_P(ThirdParty, WholeCharacters, ::testing::ValuesIn(kWhole),
                         [](const ::testing::TestParamInfo<WholeCase>& i) { return std::string(i.param.name); });

// The heads that land well say nothing.
TEST_P(Heads, AGoodFitSaysNothing) {
  const std::string mesh = kModels + GetParam().path;
  MeshData m;
  std::string err;
  ASSERT_TRUE(loadMesh(mesh, m, &err)) << err;
  EXPECT_EQ(fitHead(HeadParams{}, mesh, m).unsure, "");
}

}  // namespace
}  // namespace ponyhop

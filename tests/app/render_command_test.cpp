// The headless render path end to end: the head renders lit and in frame, runs are
// byte-identical, OBJ and glTF heads look alike, bad input never touches existing output.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "common/run_util.h"
#include "engine/image.h"
#include "engine/image_diff.h"
#include "engine/render_session.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
using testing::readFile;
using testing::runPonyhop;
using testing::scratch;
using testing::writeFile;

const char* kSmall = "--size 320x240 --set render.samples=4 --set light.shadow_size=1024";

double luminance(const uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

// Renders frame `t` of a scene in-process.
Image renderScene(const Scene& scene, double t) {
  RenderSession session(scene);
  session.simulateTo(t);
  Image img;
  img.width = session.width();
  img.height = session.height();
  session.renderFrame(t, img.rgba);
  return img;
}

Scene smallHeadScene() {
  Scene s = loadScene("assets/scenes/head.json");
  s.render.width = 320;
  s.render.height = 240;
  s.light.shadow_size = 1024;
  return s;
}

TEST(RenderCommand, HeadCoversAPlausibleShareAndIsLit) {
  const Scene with_head = smallHeadScene();
  Scene empty = with_head;
  empty.head.reset();
  const Image a = renderScene(with_head, 0.0);
  const Image b = renderScene(empty, 0.0);
  ASSERT_EQ(a.rgba.size(), b.rgba.size());
  // The head's pixels: where the picture differs from the same scene without a head (ignoring
  // faint shadow on the ground, which changes luminance only a little).
  long covered = 0;
  double sum = 0.0, sum2 = 0.0;
  for (size_t i = 0; i < a.rgba.size(); i += 4) {
    const double d = std::abs(luminance(&a.rgba[i]) - luminance(&b.rgba[i])) +
                     std::abs(int(a.rgba[i]) - int(b.rgba[i])) + std::abs(int(a.rgba[i + 2]) - int(b.rgba[i + 2]));
    if (d > 30.0) {
      ++covered;
      const double l = luminance(&a.rgba[i]);
      sum += l;
      sum2 += l * l;
    }
  }
  const double share = double(covered) / (a.width * a.height);
  EXPECT_GT(share, 0.05) << "the head is too small or out of frame";
  EXPECT_LT(share, 0.6) << "the head fills the frame";
  ASSERT_GT(covered, 0);
  const double mean = sum / covered, stddev = std::sqrt(std::max(0.0, sum2 / covered - mean * mean));
  EXPECT_GT(mean, 60.0) << "the head is too dark";
  EXPECT_LT(mean, 250.0) << "the head is blown out";
  EXPECT_GT(stddev, 12.0) << "the head is flat: no shading";
}

TEST(RenderCommand, SameInputsGiveByteIdenticalFrames) {
  const std::string a = scratch("identical_a"), b = scratch("identical_b");
  const std::string common = std::string("render assets/scenes/ponytail.json --frames 3 ") + kSmall;
  ASSERT_EQ(runPonyhop(common + " --out " + a, "identical_a").code, 0);
  const auto rb = runPonyhop(common + " --out " + b, "identical_b");
  ASSERT_EQ(rb.code, 0) << rb.out;
  for (int i = 0; i < 3; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "/frame_%05d.png", i);
    const std::string fa = readFile(a + name), fb = readFile(b + name);
    ASSERT_FALSE(fa.empty()) << a + name;
    EXPECT_EQ(fa, fb) << "frame " << i << " differs between runs";
  }
  EXPECT_FALSE(fs::exists(a + "/frame_00003.png"));
  EXPECT_NE(rb.out.find("simulate"), std::string::npos) << "summary line missing: " << rb.out;
  EXPECT_NE(rb.out.find("encode"), std::string::npos);
}

TEST(RenderCommand, ObjAndGltfHeadsRenderAlike) {
  // The same geometry in both files; only the glTF carries the hair region (assets/head/README.md).
  Scene gltf = smallHeadScene();
  gltf.head->scalp_hair = false;
  Scene obj = gltf;
  obj.head->mesh = "assets/head/head.obj";
  const Image a = renderScene(gltf, 0.7), b = renderScene(obj, 0.7);
  Image diff;
  const DiffResult r = compareImages(a, b, DiffOptions{}, &diff);
  EXPECT_TRUE(r.pass) << r.differing << " pixels differ (" << r.share * 100 << " %)";
}

TEST(RenderCommand, ShorterRunRemovesStaleFramesAndMakesAVideo) {
  const std::string out = scratch("rerun");
  const std::string base = std::string("render assets/scenes/head.json ") + kSmall + " --out " + out;
  ASSERT_EQ(runPonyhop(base + " --frames 4", "rerun1").code, 0);
  const auto r = runPonyhop(base + " --frames 2 --video " + out + ".mp4", "rerun2");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(out + "/frame_00001.png"));
  EXPECT_FALSE(fs::exists(out + "/frame_00002.png")) << "a frame of the earlier, longer run is left";
  EXPECT_GT(fs::file_size(out + ".mp4"), 1000u);
  for (const auto& e : fs::directory_iterator(fs::path(out).parent_path())) {
    EXPECT_EQ(e.path().string().find("rerun.partial"), std::string::npos) << "staging left: " << e.path();
  }
}

// Each bad input: a clear message naming what is wrong, a non-zero exit, and the existing output
// folder exactly as it was.
TEST(RenderCommand, BadInputLeavesExistingOutputUntouched) {
  const std::string dir = scratch("bad_input");
  const std::string out = dir + "/out";
  writeFile(out + "/frame_00000.png", "precious");
  writeFile(dir + "/unknown_key.json", R"({"physics": {"dtt": 0.01}})");
  writeFile(dir + "/wrong_type.json", R"({"physics": {"dt": "small"}})");
  writeFile(dir + "/out_of_range.json", R"({"anchor": {}, "chain": {"links": 0}})");
  writeFile(dir + "/missing_mesh.json", R"({"head": {"mesh": "nowhere/head.obj"}})");
  writeFile(dir + "/broken.json", R"({"physics": )");
  writeFile(dir + "/not_a_mesh.obj", "this is not a mesh\n");
  writeFile(dir + "/bad_mesh.json", R"({"head": {"mesh": "not_a_mesh.obj"}})");
  writeFile(dir + "/nan.json", R"({"anchor": {}, "chain": {}})");
  struct Case {
    std::string args, expect;
  } cases[] = {
      {dir + "/unknown_key.json", "physics.dtt: unknown key"},
      {dir + "/wrong_type.json", "physics.dt: must be a number"},
      {dir + "/out_of_range.json", "chain.links"},
      {dir + "/missing_mesh.json", "head.mesh: file not found"},
      {dir + "/broken.json", "not valid JSON"},
      {dir + "/bad_mesh.json", "not_a_mesh.obj"},
      {dir + "/nan.json --set chain.mass=nan", "chain.mass"},
      {dir + "/nan.json --set physics.dt=-1", "physics.dt"},
      {dir + "/no_such_scene.json", "no_such_scene.json"},
      {"assets/scenes/head.json --size 321x240", "even"},
      {"assets/scenes/head.json --size big", "--size"},
  };
  int n = 0;
  for (const auto& c : cases) {
    const auto r = runPonyhop("render " + c.args + " --frames 2 --out " + out, "bad" + std::to_string(n++));
    EXPECT_EQ(r.code, 2) << c.args;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << " said:\n" << r.out;
    EXPECT_EQ(readFile(out + "/frame_00000.png"), "precious") << c.args;
    EXPECT_FALSE(fs::exists(out + "/frame_00001.png")) << c.args;
  }
}

}  // namespace
}  // namespace ponyhop

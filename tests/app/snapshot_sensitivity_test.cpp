// The comparator on real frames at the goldens' size: what must pass (a different anti-aliasing
// pattern, noise below the threshold) and what must fail (a camera turned by half a degree, the
// ponytail one step later, a visibly different colour, a missing link).
#include <gtest/gtest.h>

#include <cmath>

#include "app/ui_headless.h"
#include "engine/image.h"
#include "engine/image_diff.h"
#include "engine/render_session.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

constexpr double kT = 2.7;  // s, the ponytail mid-swing (as in the golden ponytail_swing)

Scene baseScene() {
  Scene s = loadScene("assets/scenes/ponytail.json");
  s.render.width = 320;
  s.render.height = 180;
  s.render.samples = 4;
  s.light.shadow_size = 1024;
  return s;
}

Image render(const Scene& scene, double t, int extra_steps = 0) {
  RenderSession session(scene);
  EXPECT_TRUE(session.simulateTo(t));
  for (int i = 0; i < extra_steps; ++i) session.sim().step();
  Image img;
  img.width = session.width();
  img.height = session.height();
  session.renderFrame(t, img.rgba);
  return img;
}

DiffResult compare(const Image& a, const Image& b) {
  const DiffResult r = compareImages(a, b, DiffOptions{});
  std::printf("  %s\n", r.message.c_str());  // the margin, for the log
  return r;
}

class SnapshotSensitivity : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { base_ = new Image(render(baseScene(), kT)); }
  static void TearDownTestSuite() { delete base_; }
  static Image* base_;
};
Image* SnapshotSensitivity::base_ = nullptr;

TEST_F(SnapshotSensitivity, SameRenderPasses) { EXPECT_TRUE(compare(*base_, render(baseScene(), kT)).pass); }

TEST_F(SnapshotSensitivity, DifferentAntialiasingPatternPasses) {
  Scene s = baseScene();
  s.render.samples = 8;
  const DiffResult r = compare(*base_, render(s, kT));
  EXPECT_TRUE(r.pass) << r.message;
}

TEST_F(SnapshotSensitivity, NoiseBelowThresholdPasses) {
  Image noisy = *base_;
  uint32_t seed = 12345;
  for (size_t i = 0; i < noisy.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    seed = seed * 1664525u + 1013904223u;
    const int d = static_cast<int>((seed >> 16) % 5) - 2;  // -2..2
    noisy.rgba[i] = static_cast<uint8_t>(std::clamp(int(noisy.rgba[i]) + d, 0, 255));
  }
  const DiffResult r = compare(*base_, noisy);
  EXPECT_TRUE(r.pass) << r.message;
}

TEST_F(SnapshotSensitivity, CameraTurnedHalfADegreeFails) {
  Scene s = baseScene();
  // Turn the view about the vertical through the eye by 0.5 degrees.
  const Eigen::Vector3d eye = s.camera.position, to = s.camera.target - eye;
  s.camera.target = eye + Eigen::AngleAxisd(0.5 * M_PI / 180.0, Eigen::Vector3d::UnitZ()) * to;
  const DiffResult r = compare(*base_, render(s, kT));
  EXPECT_FALSE(r.pass) << r.message;
}

TEST_F(SnapshotSensitivity, PonytailOneStepLaterFails) {
  const DiffResult r = compare(*base_, render(baseScene(), kT, 1));
  EXPECT_FALSE(r.pass) << r.message;
}

TEST_F(SnapshotSensitivity, VisiblyDifferentHairColourFails) {
  Scene s = baseScene();
  s.chain->color = s.chain->color + Eigen::Vector3d(0.12, 0.12, 0.12);
  const DiffResult r = compare(*base_, render(s, kT));
  EXPECT_FALSE(r.pass) << r.message;
}

TEST_F(SnapshotSensitivity, MissingLinkFails) {
  Scene s = baseScene();
  s.chain->links -= 1;
  const DiffResult r = compare(*base_, render(s, kT));
  EXPECT_FALSE(r.pass) << r.message;
}

// The panel beside the scene: the same frame with one parameter changed (a value printed in a
// slider) must fail.
Image renderPanel(const Scene& scene) {
  HeadlessUi ui(scene, 320, 360);
  ui.sim().readouts().show_wall_clock = false;  // the step and frame times differ run to run
  UiInput in;
  ui.frame(in, nullptr, 0.0);
  Image img;
  img.width = ui.width();
  img.height = ui.height();
  ui.frame(in, &img.rgba, 0.5);
  return img;
}

TEST(SnapshotSensitivityPanel, PanelWithADifferentValueFails) {
  const Scene a = baseScene();
  Scene b = a;
  b.chain->stiffness *= 1.5;  // shown near the top of the panel's Look section
  const Image pa = renderPanel(a);
  EXPECT_TRUE(compare(pa, renderPanel(a)).pass) << "the panel frame is not repeatable";
  const DiffResult r = compare(pa, renderPanel(b));
  EXPECT_FALSE(r.pass) << r.message;
}

}  // namespace
}  // namespace ponyhop

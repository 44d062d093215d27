// render.colliders: the collision shapes and the contacts drawn over the picture. A scene with
// collisions shows them (cyan wireframes, red contact normals); a scene without any is unchanged.
#include <gtest/gtest.h>

#include <cstdio>

#include "engine/image_diff.h"
#include "engine/render_session.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

struct Counts {
  long changed = 0;  // pixels that differ from the picture without the overlay
  long cyan = 0;     // of those, cyan-ish (the wireframes)
  long red = 0;      // red-ish (the contacts)
};

Counts overlay(const std::string& scene_path, double t) {
  Counts c;
  std::vector<uint8_t> plain, with;
  for (const bool on : {false, true}) {
    Scene scene = loadScene(scene_path, {{"render.colliders", on ? "true" : "false"}});
    scene.render.width = 320;
    scene.render.height = 180;
    scene.render.samples = 1;
    RenderSession session(scene);
    EXPECT_TRUE(session.simulateTo(t)) << session.status();
    session.renderFrame(t, on ? with : plain);
  }
  for (size_t i = 0; i + 3 < plain.size(); i += 4) {
    const int r = with[i], g = with[i + 1], b = with[i + 2];
    if (r == plain[i] && g == plain[i + 1] && b == plain[i + 2]) continue;
    ++c.changed;
    if (b > 150 && g > 150 && r < 120) ++c.cyan;
    if (r > 150 && g < 100 && b < 100) ++c.red;
  }
  return c;
}

TEST(CollidersOverlay, AFallenHopperShowsItsShapesAndContacts) {
  const Counts c = overlay("assets/scenes/hopper_fall.json", 5.0);
  std::printf("hopper_fall at 5 s: %ld pixels changed, %ld cyan, %ld red\n", c.changed, c.cyan, c.red);
  EXPECT_GT(c.cyan, 100) << "the wireframes";
  EXPECT_GT(c.red, 5) << "the contacts where it lies";
}

TEST(CollidersOverlay, ASceneWithoutCollisionsIsUnchanged) {
  const Counts c = overlay("assets/scenes/hopper.json", 1.0);
  EXPECT_EQ(c.changed, 0);
}

}  // namespace
}  // namespace ponyhop

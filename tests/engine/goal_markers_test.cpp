// render.goals: each goal drawn as a marker over the picture (docs/GOALS.md, "Markers"). Off, the
// picture is the one without goals; on, a goal's marker is magenta while its time is near, dim
// otherwise, and on the frame at its time a yellow line runs from the goal's point to it.
#include <gtest/gtest.h>

#include <cstdio>

#include "engine/render_session.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

// A 3-link chain falling from a fixed anchor at the origin, seen from 0.5 m; one goal
// for the tip at t = 0.5 s, 8 cm below the anchor (the tip is elsewhere then: the line is long).
Scene markerScene(const char* goals_on) {
  Scene s = parseSceneText(R"({"anchor": {}, "chain": {"links": 3, "direction": [1, 0, 0]},
      "camera": {"position": [0.3, -0.4, 0.0], "target": [0.03, 0.0, -0.08]},
      "goals": [{"t": 0.5, "point": "tip", "position": [0.0, 0.0, -0.08]}]})",
                           "markers.json", {parseOverride(std::string("render.goals=") + goals_on)});
  s.render.width = 320;
  s.render.height = 180;
  s.render.samples = 1;
  s.render.fps = 30;
  return s;
}

struct MarkerCounts {
  long changed = 0;  // pixels that differ from the picture without markers
  long magenta = 0;  // the marker, bright
  long yellow = 0;   // the miss line
};

MarkerCounts markerPixels(double t) {
  std::vector<uint8_t> plain, with;
  for (const bool on : {false, true}) {
    RenderSession session(markerScene(on ? "true" : "false"));
    EXPECT_TRUE(session.simulateTo(t)) << session.status();
    session.renderFrame(t, on ? with : plain);
  }
  MarkerCounts c;
  for (size_t i = 0; i + 3 < plain.size(); i += 4) {
    const int r = with[i], g = with[i + 1], b = with[i + 2];
    if (r == plain[i] && g == plain[i + 1] && b == plain[i + 2]) continue;
    ++c.changed;
    if (r > 200 && b > 180 && g < 110) ++c.magenta;
    if (r > 200 && g > 170 && b < 90) ++c.yellow;
  }
  std::printf("t = %.2f s: %ld pixels changed, %ld magenta, %ld yellow\n", t, c.changed, c.magenta, c.yellow);
  return c;
}

TEST(GoalMarkers, AtTheGoalsTimeTheMarkerIsBrightWithTheMissLine) {
  const MarkerCounts c = markerPixels(0.5);
  EXPECT_GT(c.magenta, 30) << "the marker";
  EXPECT_GT(c.yellow, 10) << "the line from the tip to the marker";
}

TEST(GoalMarkers, FarFromItsTimeTheMarkerIsFaintWithoutALine) {
  const MarkerCounts c = markerPixels(0.1);
  EXPECT_GT(c.changed, 30) << "the faint marker is drawn";
  EXPECT_EQ(c.magenta, 0);
  EXPECT_EQ(c.yellow, 0);
}

TEST(GoalMarkers, OffByDefaultDrawsNothing) {
  Scene without = markerScene("false");
  without.goals.clear();
  Scene with = markerScene("false");
  EXPECT_FALSE(parseSceneText(R"({"anchor": {}})", "d.json").render.goals);
  without.render = with.render;
  std::vector<uint8_t> a, b;
  RenderSession plain(without), off(with);
  ASSERT_TRUE(plain.simulateTo(0.5) && off.simulateTo(0.5));
  plain.renderFrame(0.5, a);
  off.renderFrame(0.5, b);
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace ponyhop

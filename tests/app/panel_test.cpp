// The tuning panel driven headless with synthetic mouse and keyboard input, the way a user would
// use it: drag sliders, press buttons and keys, pull on the hair, save and load presets. Most tests
// build ImGui frames without GL (fast); the last ones render real frames through OSMesa.
#include "app/panel.h"

#include <gtest/gtest.h>
#include <imgui.h>

#include <cmath>
#include <filesystem>
#include <thread>

#include "app/ui_headless.h"
#include "app/ui_sim.h"
#include "common/out_util.h"
#include "common/run_util.h"
#include "engine/asset_loader.h"
#include "engine/frame_writer.h"
#include "engine/render_session.h"
#include "sim/goal_solve.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

// A panel without GL: ImGui frames are built (and all logic runs) but nothing is drawn.
struct Harness {
  explicit Harness(const std::string& scene_path) : sim(loadScene(scene_path)), panel(sim) {
    sim.setStepBudgetMs(0.0);
    // The raw fields these tests drag (the artist's Look section is tested on its own).
    panel.setSectionOpen("Look", false);
    panel.setSectionOpen("Presets", false);
    panel.setSectionOpen("Ponytail: every field", true);
    panel.setSectionOpen("Physics", true);
    frame();  // first frame: lay out the widgets
  }

  void frame() {
    feedInput(in);
    ImGui::NewFrame();
    panel.build(layout);
    ImGui::Render();
    in.wheel = 0.0f;
  }
  void frames(int n) {
    for (int i = 0; i < n; ++i) frame();
  }
  WidgetRect rect(const std::string& id) {
    auto r = panel.widgetRect(id);
    EXPECT_TRUE(r.has_value()) << "widget '" << id << "' was not drawn";
    return r.value_or(WidgetRect{});
  }
  void moveTo(float x, float y) {
    in.mouse_x = x;
    in.mouse_y = y;
    frame();
  }
  // Press at (x0, y0), move in steps to (x1, y1), release: a drag as a hand does it.
  void drag(float x0, float y0, float x1, float y1, int steps = 8) {
    moveTo(x0, y0);
    in.mouse_down[0] = true;
    frame();
    for (int i = 1; i <= steps; ++i) moveTo(x0 + (x1 - x0) * i / steps, y0 + (y1 - y0) * i / steps);
    in.mouse_down[0] = false;
    frame();
  }
  void click(const std::string& id) {
    const WidgetRect r = rect(id);
    drag(r.cx(), r.cy(), r.cx(), r.cy(), 1);
  }
  void press(int imgui_key) {
    in.keys_down = {imgui_key};
    frame();
    in.keys_down.clear();
    frame();
  }

  PanelContext ctx;  // first: the ImGui context outlives the panel
  LiveSim sim;
  Panel panel;
  PanelLayout layout{1600, 1000, Panel::kDefaultWidth};
  UiInput in = [] {
    UiInput i;
    i.width = 1600;
    i.height = 1000;
    return i;
  }();
};

Eigen::Vector3d tip(const LiveSim& sim) { return sim.runtime().chain()->tip(sim.runtime().world()); }

TEST(PanelTest, DraggingTheLinkCountSliderRebuildsTheChain) {
  Harness h("assets/scenes/chain.json");
  ASSERT_EQ(h.sim.linkCount(), 8);
  h.frames(10);
  const WidgetRect r = h.rect("chain.links");
  EXPECT_GE(r.x0, float(h.layout.sceneWidth())) << "the slider belongs to the panel at the right";
  // Drag the slider's grab to the right end of its track.
  h.drag(r.cx(), r.cy(), r.x1 + 40.0f, r.cy());
  EXPECT_GT(h.sim.linkCount(), 8) << "dragging right adds links";
  EXPECT_EQ(h.sim.linkCount(), h.sim.applied().chain->links) << "the world has the chain the panel shows";
  EXPECT_EQ(h.sim.lastApply(), ApplyKind::Restart) << "a new link count rebuilds the chain from t = 0";
  // ... and back to the left end: one link.
  const WidgetRect r2 = h.rect("chain.links");
  h.drag(r2.cx(), r2.cy(), r2.x0 - 40.0f, r2.cy());
  EXPECT_EQ(h.sim.linkCount(), 1);
  h.frames(5);  // the rebuilt chain runs
  EXPECT_TRUE(h.sim.ok()) << h.sim.stopMessage();
  EXPECT_GT(h.sim.simTime(), 0.0);
  // Its reset button brings the default (8) back.
  h.click("reset:chain.links");
  EXPECT_EQ(h.sim.linkCount(), 8);
}

TEST(PanelTest, DraggingTheGravitySliderChangesTheMotionWithoutRestarting) {
  Harness reference("assets/scenes/chain.json");
  reference.frames(30);
  const Eigen::Vector3d tip_reference = tip(reference.sim);
  const double time_reference = reference.sim.simTime();

  Harness h("assets/scenes/chain.json");
  h.frames(10);
  const double t_before = h.sim.simTime();
  const WidgetRect g = h.rect("physics.gravity");
  // The z component is the third of the three drag boxes; drag it right: gravity gets weaker.
  const float z_x = g.x0 + (g.x1 - g.x0) * 5.0f / 6.0f;
  h.drag(z_x, g.cy(), z_x + 120.0f, g.cy(), 6);
  const double gz = h.sim.applied().physics.gravity.z();
  EXPECT_GT(gz, -9.0) << "the slider changed gravity";
  EXPECT_LT(gz, 0.0);
  EXPECT_EQ(h.sim.lastApply(), ApplyKind::KeepState) << "gravity applies without restarting";
  EXPECT_GE(h.sim.simTime(), t_before) << "simulated time went on through the edit";
  while (h.sim.simTime() < time_reference - 1e-9) h.frame();  // as many frames as the reference
  ASSERT_NEAR(h.sim.simTime(), time_reference, 1e-9);
  EXPECT_GT((tip(h.sim) - tip_reference).norm(), 0.01) << "weaker gravity: a different swing";
  EXPECT_TRUE(h.sim.ok()) << h.sim.stopMessage();
}

TEST(PanelTest, HairKnobsApplyLiveWithoutRebuildingTheSim) {
  Harness h("assets/scenes/ponytail.json");
  h.frames(10);
  const Sim* before = &h.sim.runtime();
  const double t_before = h.sim.simTime();
  h.sim.edited().chain->hair.strands = 20;
  h.sim.edited().chain->hair.tie_color = Eigen::Vector3d(0.1, 0.2, 0.9);
  EXPECT_EQ(h.sim.applyEdits(), ApplyKind::Live) << "drawing fields need no rebuild";
  EXPECT_EQ(&h.sim.runtime(), before) << "the same world goes on";
  EXPECT_GE(h.sim.simTime(), t_before);
  EXPECT_EQ(h.sim.applied().chain->hair.strands, 20);
}

TEST(PanelTest, ResetButtonAndBackspaceRestoreTheInitialState) {
  Harness h("assets/scenes/chain.json");
  const Sim fresh(loadScene("assets/scenes/chain.json"), &assimpAssets());  // the state at t = 0
  const Eigen::Vector3d tip0 = fresh.chain()->tip(fresh.world());
  const std::vector<RigidBody>& bodies0 = fresh.world().bodies();
  h.frames(40);
  ASSERT_GT((tip(h.sim) - tip0).norm(), 0.01) << "the chain swings";
  h.in.mouse_x = -100;  // no hover on the button while it is pressed from the far side
  const WidgetRect r = h.rect("reset");
  h.moveTo(r.cx(), r.cy());
  h.in.mouse_down[0] = true;
  h.frame();
  h.in.mouse_down[0] = false;
  h.panel.sim().setRunning(false);  // stop the next frame from stepping, to compare the state exactly
  h.frame();
  EXPECT_EQ(h.sim.simTime(), 0.0);
  const auto& bodies = h.sim.runtime().world().bodies();
  ASSERT_EQ(bodies.size(), bodies0.size());
  for (size_t i = 0; i < bodies.size(); ++i) {
    EXPECT_NEAR((bodies[i].x - bodies0[i].x).norm(), 0.0, 1e-12) << bodies[i].name;
    EXPECT_NEAR((bodies[i].v - bodies0[i].v).norm(), 0.0, 1e-12) << bodies[i].name;
  }
  // Space runs, Backspace resets.
  h.press(ImGuiKey_Space);
  EXPECT_TRUE(h.sim.running());
  h.frames(10);
  EXPECT_GT(h.sim.simTime(), 0.1);
  h.press(ImGuiKey_Backspace);
  EXPECT_LT(h.sim.simTime(), 0.05) << "Backspace started over (one frame has run since)";
}

TEST(PanelTest, SaveThenLoadReproducesTheParametersExactly) {
  const std::string dir = testing::scratch("panel_presets");
  const std::string path = dir + "/tuned.json";
  Harness h("assets/scenes/ponytail.json");
  // Tune a few parameters with the mouse: damping (log slider), drag, gravity.
  for (const char* key : {"chain.damping", "chain.drag"}) {
    const WidgetRect r = h.rect(key);
    h.drag(r.cx(), r.cy(), r.cx() + 37.0f, r.cy(), 4);
  }
  const WidgetRect g = h.rect("physics.gravity");
  h.drag(g.x0 + 10.0f, g.cy(), g.x0 + 33.0f, g.cy(), 3);  // the x component
  const Scene tuned = h.sim.edited();
  ASSERT_NE(sceneToJson(tuned), sceneToJson(loadScene("assets/scenes/ponytail.json"))) << "the drags changed something";
  ASSERT_TRUE(h.sim.error().empty()) << h.sim.error();

  h.panel.setSectionOpen("Presets", true);
  h.frame();
  h.panel.presetPath() = path;
  h.click("save");
  ASSERT_TRUE(std::filesystem::exists(path)) << h.panel.presetMessage();

  // Change something else, then load the preset back.
  const WidgetRect s = h.rect("chain.stiffness");
  h.drag(s.cx(), s.cy(), s.x0 - 20.0f, s.cy(), 3);
  ASSERT_NE(sceneToJson(h.sim.edited()), sceneToJson(tuned));
  h.click("load");
  EXPECT_EQ(sceneToJson(h.sim.applied()), sceneToJson(tuned)) << "every parameter, bit for bit";
  EXPECT_EQ(sceneToJson(loadScene(path)), sceneToJson(tuned));
  EXPECT_EQ(h.sim.simTime(), 0.0) << "a loaded preset starts at t = 0";
}

TEST(PanelTest, ADivergingValueIsCaughtPausedAndResetRecovers) {
  Harness h("assets/scenes/chain.json");
  h.frames(3);
  // A huge time step with a stiff bending spring, no stabilization and no step control: the run
  // blows up.
  Scene& s = h.sim.edited();
  s.physics.dt = 0.1;
  s.physics.integrator = Integrator::SymplecticEuler;
  s.physics.stabilization = Stabilization::None;
  s.chain->stiffness = 100.0;
  s.physics.max_step_rotation = 0.0;  // no automatic substeps to rescue it
  h.frames(60);
  EXPECT_FALSE(h.sim.ok());
  EXPECT_FALSE(h.sim.running()) << "a stopped run pauses";
  EXPECT_NE(h.sim.stopMessage().find("Stopped at simulated time"), std::string::npos) << h.sim.stopMessage();
  EXPECT_NE(h.sim.stopMessage().find("stage"), std::string::npos) << "the world's message names the stage";
  // Put the values back (their reset buttons) and press Reset.
  h.panel.setSectionOpen("Physics", true);
  h.frame();
  for (const char* key :
       {"physics.dt", "physics.integrator", "physics.stabilization", "physics.max_step_rotation", "chain.stiffness"}) {
    h.click(std::string("reset:") + key);
  }
  h.click("reset");
  EXPECT_TRUE(h.sim.ok()) << h.sim.stopMessage();
  EXPECT_TRUE(h.sim.running()) << "reset resumes a run that stopped itself";
  h.frames(30);
  EXPECT_TRUE(h.sim.ok()) << h.sim.stopMessage();
  EXPECT_GT(h.sim.simTime(), 0.4);
}

TEST(PanelTest, AnInvalidEditIsNotAppliedAndSaysWhy) {
  Harness h("assets/scenes/chain.json");
  h.sim.edited().chain->length = -1.0;
  h.frame();
  EXPECT_NE(h.sim.error().find("chain.length"), std::string::npos) << h.sim.error();
  EXPECT_DOUBLE_EQ(h.sim.applied().chain->length, 0.05) << "the running scene keeps its last good value";
  h.sim.edited().physics.gravity.z() = std::nan("");
  h.sim.edited().chain->length = 0.05;
  h.frame();
  EXPECT_NE(h.sim.error().find("physics.gravity"), std::string::npos) << h.sim.error();
  EXPECT_TRUE(h.sim.ok());
  h.sim.edited().physics.gravity.z() = -9.81;
  h.frame();
  EXPECT_TRUE(h.sim.error().empty()) << h.sim.error();
}

// Projects a world point into the scene view (pixels, top-left origin).
Eigen::Vector2f toPixel(const Camera& cam, const Eigen::Vector3d& p, const PanelLayout& l) {
  const double aspect = double(l.sceneWidth()) / l.height;
  const Eigen::Vector4d c =
      cam.projection(aspect, 0.01, 100.0) * cam.view() * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
  return {float((c.x() / c.w() * 0.5 + 0.5) * l.sceneWidth()), float((0.5 - c.y() / c.w() * 0.5) * l.height)};
}

TEST(PanelTest, MouseOrbitsZoomsAndPullsOnALink) {
  Harness reference("assets/scenes/chain.json");
  Harness h("assets/scenes/chain.json");
  // Grab the last link's centre and pull it up and sideways for a while.
  const Chain& chain = *h.sim.runtime().chain();
  const Eigen::Vector3d centre = h.sim.runtime().world().body(chain.links.back()).x;
  const Eigen::Vector2f px = toPixel(h.panel.camera(), centre, h.layout);
  ASSERT_LT(px.x(), float(h.layout.sceneWidth()));
  h.moveTo(px.x(), px.y());
  h.in.mouse_down[0] = true;
  h.frame();
  EXPECT_TRUE(h.sim.perturbation().active()) << "the click caught the link";
  EXPECT_EQ(h.sim.perturbation().body, chain.links.back());
  for (int i = 1; i <= 20; ++i) h.moveTo(px.x() + 6.0f * i, px.y() - 8.0f * i);
  h.in.mouse_down[0] = false;
  h.frame();
  EXPECT_FALSE(h.sim.perturbation().active()) << "release lets go";
  while (reference.sim.simTime() < h.sim.simTime() - 1e-9) reference.frame();
  ASSERT_NEAR(reference.sim.simTime(), h.sim.simTime(), 1e-9);
  EXPECT_GT((tip(h.sim) - tip(reference.sim)).norm(), 0.02) << "the pull moved the chain";
  EXPECT_FALSE(h.panel.freeView()) << "pulling does not move the camera";

  // Drag on empty space orbits; the wheel zooms.
  const Eigen::Vector3d eye0 = h.panel.camera().eye;
  h.drag(40.0f, 40.0f, 140.0f, 60.0f);
  EXPECT_TRUE(h.panel.freeView());
  EXPECT_GT((h.panel.camera().eye - eye0).norm(), 0.1) << "orbit";
  const double d0 = (h.panel.camera().eye - h.panel.camera().target).norm();
  h.in.wheel = 3.0f;
  h.frame();
  EXPECT_LT((h.panel.camera().eye - h.panel.camera().target).norm(), 0.8 * d0) << "zoom in";
}

TEST(PanelTest, EachChainOfATwoChainSceneHasItsOwnFieldsAndLinksToPull) {
  // pigtails.json holds two chains (a `chains` list, no `chain`): each gets its own section, and
  // the mouse catches either chain's links.
  Harness h("assets/scenes/pigtails.json");
  ASSERT_EQ(h.sim.runtime().chains().size(), 2u);
  h.frames(5);
  const Chain& second = h.sim.runtime().chains()[1];
  const int grabbed = second.links.back();
  const Eigen::Vector2f px = toPixel(h.panel.camera(), h.sim.runtime().world().body(grabbed).x, h.layout);
  ASSERT_LT(px.x(), float(h.layout.sceneWidth()));
  h.moveTo(px.x(), px.y());
  h.in.mouse_down[0] = true;
  h.frame();
  EXPECT_TRUE(h.sim.perturbation().active()) << "the click caught the second chain's last link";
  EXPECT_EQ(h.sim.perturbation().body, grabbed);
  h.in.mouse_down[0] = false;
  h.frame();

  h.panel.setSectionOpen("Chain chains.1: every field", true);
  h.frames(2);
  const WidgetRect r = h.rect("chains.1.links");
  EXPECT_GE(r.x0, float(h.layout.sceneWidth())) << "the slider belongs to the panel at the right";
  h.drag(r.cx(), r.cy(), r.x0 - 40.0f, r.cy());  // to the left end of the track: one link
  ASSERT_EQ(h.sim.runtime().chains().size(), 2u);
  EXPECT_EQ(h.sim.applied().chains[1].links, 1);
  EXPECT_EQ(h.sim.runtime().chains()[1].links.size(), 1u) << "the world has the chain the panel shows";
  EXPECT_EQ(h.sim.runtime().chains()[0].links.size(), 8u) << "the other chain keeps its links";
  h.frames(5);
  EXPECT_TRUE(h.sim.ok()) << h.sim.stopMessage();
}

// --- With GL (OSMesa): the panel in real frames. -----------------------------------------------

struct RegionStats {
  double stddev = 0.0;  // of luminance
  int colours = 0;      // distinct (quantized) colours
};
RegionStats regionStats(const std::vector<uint8_t>& rgba, int w, int x0, int x1, int y0, int y1) {
  double sum = 0, sum2 = 0;
  std::vector<bool> seen(4096, false);
  int n = 0, colours = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = &rgba[(size_t(y) * w + x) * 4];
      const double l = 0.3 * p[0] + 0.59 * p[1] + 0.11 * p[2];
      sum += l;
      sum2 += l * l;
      ++n;
      const int q = (p[0] >> 4) << 8 | (p[1] >> 4) << 4 | (p[2] >> 4);
      if (!seen[size_t(q)]) seen[size_t(q)] = true, ++colours;
    }
  }
  const double mean = sum / n;
  return {std::sqrt(std::max(0.0, sum2 / n - mean * mean)), colours};
}

TEST(PanelTest, HeadlessFramesShowTheSceneAndThePanel) {
  Scene scene = loadScene("assets/scenes/ponytail.json");
  HeadlessUi ui(scene, 480, 540);
  ASSERT_EQ(ui.width(), 480 + Panel::kDefaultWidth);
  std::vector<uint8_t> rgba;
  UiInput in;
  for (int i = 0; i < 3; ++i) ui.frame(in, &rgba);
  ASSERT_EQ(rgba.size(), size_t(ui.width()) * ui.height() * 4);
  const RegionStats scene_px = regionStats(rgba, ui.width(), 0, 480, 0, 540);
  const RegionStats panel_px = regionStats(rgba, ui.width(), 480, ui.width(), 0, 540);
  EXPECT_GT(scene_px.stddev, 5.0) << "the scene view is not blank";
  EXPECT_GT(panel_px.stddev, 5.0) << "the panel is not blank";
  EXPECT_GT(panel_px.colours, 12) << "text, sliders and headers";
  std::string err;
  EXPECT_TRUE(
      writePngAtomic(testing::scratch("panel_frames") + "/panel.png", ui.width(), ui.height(), rgba.data(), &err))
      << err;

  // Clicking in the panel of a rendered frame works the same: pause with the Run button.
  const WidgetRect run = ui.panel().widgetRect("run").value();
  in.mouse_x = run.cx();
  in.mouse_y = run.cy();
  ui.frame(in);
  in.mouse_down[0] = true;
  ui.frame(in);
  in.mouse_down[0] = false;
  ui.frame(in);
  EXPECT_FALSE(ui.sim().running());
}

TEST(PanelTest, ASavedPresetRendersTheSameFramesHeadless) {
  const std::string dir = testing::scratch("panel_same_frames");
  Scene scene = loadScene("assets/scenes/chain.json");
  scene.render.width = 160;
  scene.render.height = 120;
  scene.render.samples = 1;
  {
    LiveSim sim(scene);
    sim.edited().chain->damping = 0.0123;
    sim.edited().physics.gravity = Eigen::Vector3d(1.5, 0.0, -7.0);
    sim.applyEdits();
    ASSERT_TRUE(sim.save(dir + "/saved.json")) << sim.error();
  }
  Scene tuned = scene;
  tuned.chain->damping = 0.0123;
  tuned.physics.gravity = Eigen::Vector3d(1.5, 0.0, -7.0);
  const Scene loaded = loadScene(dir + "/saved.json");
  std::vector<uint8_t> a, b;
  {
    RenderSession s(tuned);
    s.simulateTo(0.5);
    s.renderFrame(0.5, a);
  }
  {
    RenderSession s(loaded);
    s.simulateTo(0.5);
    s.renderFrame(0.5, b);
  }
  EXPECT_EQ(a, b) << "the same parameters render the same pixels";
}

TEST(PanelTest, RenderUiWritesAFrameWithThePanel) {
  const std::string dir = testing::scratch("render_ui");
  const auto r = testing::runPonyhop("render assets/scenes/ponytail.json --ui --frames 1 --size 640x360 --out " + dir,
                                     "render_ui");
  ASSERT_EQ(r.code, 0) << r.out;
  std::string err;
  const auto img = readPng(dir + "/frame_00000.png", &err);
  ASSERT_TRUE(img.has_value()) << err;
  EXPECT_EQ(img->width, 640 + Panel::kDefaultWidth);
  EXPECT_EQ(img->height, 360);
  const RegionStats scene_px = regionStats(img->rgba, img->width, 0, 640, 0, 360);
  const RegionStats panel_px = regionStats(img->rgba, img->width, 640, img->width, 0, 360);
  EXPECT_GT(scene_px.stddev, 5.0);
  EXPECT_GT(panel_px.colours, 12);
}

// The Goals section (docs/GOALS.md, "In the panel"): a goal's position dragged with its widget moves
// the goal in the running scene, and Solve runs the goal solve in the background and applies the
// guide it finds, which then meets the edited goal.
TEST(PanelTest, EditingAGoalAndPressingSolveAppliesAGuideThatMeetsIt) {
  Scene s = parseSceneText(R"({"anchor": {}, "chain": {"links": 3, "direction": [1, 0, 0]}})", "three.json");
  Sim free(s);
  free.advanceTo(0.25);
  const Eigen::Vector3d free_tip = free.chain()->tip(free.world());
  s.goals = {Goal{.t = 0.25, .point = "tip", .position = free_tip + Eigen::Vector3d(0.0, 0.01, 0.01)}};
  std::filesystem::create_directories(testing::testOut());
  const std::string path = testing::testOut() + "/goal.json";
  saveScene(s, path);
  Harness h(path);
  h.panel.setSectionOpen("Ponytail: every field", false);
  h.panel.setSectionOpen("Physics", false);
  h.panel.setSectionOpen("Goals", true);
  h.frames(2);
  EXPECT_FALSE(h.panel.widgetRect("goals:guide").has_value()) << "no guide yet";
  // Drag the position's middle field (y) to the right: about 1 mm a pixel.
  const WidgetRect r = h.rect("goals.0.position");
  const double y0 = h.sim.edited().goals[0].position.y();
  h.drag(r.cx(), r.cy(), r.cx() + 12.0f, r.cy());
  const double moved = h.sim.applied().goals[0].position.y() - y0;
  EXPECT_GT(moved, 0.002) << "the goal moved in the applied scene (goals apply live)";
  EXPECT_LT(moved, 0.03);
  h.click("goals:solve");
  EXPECT_TRUE(h.panel.solving());
  for (int i = 0; i < 20000 && h.panel.solving(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    h.frame();
  }
  ASSERT_FALSE(h.panel.solving());
  h.frames(2);
  EXPECT_EQ(h.panel.solveStatus().rfind("solved: 1 of 1 goals met", 0), 0u) << h.panel.solveStatus();
  ASSERT_TRUE(h.sim.applied().guide);
  EXPECT_TRUE(h.sim.applied().guide->enabled);
  EXPECT_FALSE(h.sim.applied().guide->knots.empty());
  // Checked apart from the panel: the applied scene's guide meets the edited goal.
  const GoalSolveReport replay = evaluateGoals(h.sim.applied(), nullptr);
  EXPECT_TRUE(replay.goals[0].met) << replay.goals[0].error;
  EXPECT_DOUBLE_EQ(h.sim.applied().goals[0].position.y(), y0 + moved);
  EXPECT_TRUE(h.panel.widgetRect("goals:guide").has_value()) << "the guide's switch shows once there is one";
}

}  // namespace
}  // namespace ponyhop

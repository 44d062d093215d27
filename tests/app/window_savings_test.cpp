// The window's savings (issue 37 item 2), driven headless through HeadlessUi, which composes
// with the window's own code (UiGl, ViewReuse): the panel drawn into its own texture only when it
// changed, a still final view re-presented instead of rendered again, and a kept target (the
// window's back buffer presented by rectangle copies) into which only what changed is drawn.
// Each must give the frame the plain path gives, at once: an edit shows in the frame that made it.
#include <glad/gl.h>
#include <gtest/gtest.h>
#include <imgui.h>

#include <functional>
#include <vector>

#include "app/ui_headless.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

// One scripted session of the panel: the inputs of each frame, with the widgets' places looked up
// on the frame before (the same in every run of the script).
struct PanelScript {
  std::vector<std::vector<uint8_t>> frames;
  std::vector<bool> panel_drawn;
  std::vector<UiGl::Damage> damage;
  std::vector<size_t> still, moved;  // frames after which nothing changed; frames that moved the slider
  int playing = 2;                   // frames played before the pause

  void run(HeadlessUi& ui) {
    UiInput in;
    const auto frame = [&] {
      frames.emplace_back();
      ui.frame(in, &frames.back());
      panel_drawn.push_back(ui.lastPanelDrawn());
      damage.push_back(ui.lastDamage());
      in.wheel = 0.0f;
    };
    const auto moveTo = [&](const std::string& id, float dx = 0.0f) {
      const WidgetRect r = ui.panel().widgetRect(id).value();
      in.mouse_x = r.cx() + dx;
      in.mouse_y = r.cy();
    };
    for (int i = 0; i < playing; ++i) frame();
    moveTo("run");  // pause with the button
    frame();
    in.mouse_down[0] = true;
    frame();
    in.mouse_down[0] = false;
    for (int i = 0; i < 3; ++i) frame();  // still (a tooltip shows on the first of them)
    still.push_back(frames.size() - 1);
    moveTo("speed");  // drag the playback speed's slider: the panel changes each frame
    frame();
    in.mouse_down[0] = true;
    frame();
    for (int i = 1; i <= 3; ++i) {
      moveTo("speed", -25.0f * float(i));
      frame();
      moved.push_back(frames.size() - 1);
    }
    in.mouse_down[0] = false;
    frame();
    for (int i = 0; i < 2; ++i) frame();  // still
    in.mouse_x = 100.0f;                  // out over the scene view: the slider's hover goes
    in.mouse_y = 100.0f;
    for (int i = 0; i < 2; ++i) frame();
    still.push_back(frames.size() - 1);
  }
};

Scene smallChain() {
  Scene s = loadScene("assets/scenes/chain.json");
  s.render.samples = 1;
  return s;
}

TEST(WindowSavings, ThePanelCacheGivesTheFramesDrawnWithoutIt) {
  Scene scene = smallChain();
  scene.render.quality = RenderQuality::Draft;  // the panel is what is compared; its scene costs less
  PanelScript with, without;
  {
    HeadlessUi ui(scene, 640, 360);  // wide enough for the view's overlay text
    ui.setWindowSavings(true);
    with.run(ui);
  }
  {
    HeadlessUi ui(scene, 640, 360);  // wide enough for the view's overlay text
    without.run(ui);
  }
  ASSERT_EQ(with.frames.size(), without.frames.size());
  for (size_t i = 0; i < with.frames.size(); ++i)
    EXPECT_TRUE(with.frames[i] == without.frames[i]) << "frame " << i << " differs with the panel cache";
  // The still frames reuse the panel's texture; a slider being dragged redraws it on each frame.
  for (size_t i : with.still) EXPECT_FALSE(with.panel_drawn[i]) << "frame " << i << ": the panel is still";
  for (size_t i : with.moved) EXPECT_TRUE(with.panel_drawn[i]) << "frame " << i << ": the slider moved";
  for (bool drawn : without.panel_drawn) EXPECT_TRUE(drawn);
}

TEST(WindowSavings, AStillViewIsShownAgainUntilSomethingChanges) {
  HeadlessUi ui(smallChain(), 640, 360);
  ui.setWindowSavings(true);
  ui.sim().setRunning(false);
  UiInput in;
  std::vector<uint8_t> a, b;
  const auto frame = [&](std::vector<uint8_t>& px) {
    ui.frame(in, &px);
    in.wheel = 0.0f;
    return ui.lastViewRendered();
  };
  const auto sceneColumns = [&](const std::vector<uint8_t>& px) {  // the view's pixels only
    std::vector<uint8_t> out;
    for (int y = 0; y < ui.height(); ++y)
      out.insert(out.end(), px.begin() + ptrdiff_t(y) * ui.width() * 4,
                 px.begin() + ptrdiff_t(y) * ui.width() * 4 + ui.layout().sceneWidth() * 4);
    return out;
  };
  EXPECT_TRUE(frame(a)) << "the first frame renders";
  EXPECT_FALSE(ui.renderer().stats().draft);
  EXPECT_FALSE(frame(b)) << "nothing changed: the last final view is shown again";
  EXPECT_TRUE(sceneColumns(a) == sceneColumns(b));

  // A live look edit while paused renders again, and shows.
  ui.sim().edited().chain->color = Eigen::Vector3d(0.1, 0.8, 0.2);
  EXPECT_TRUE(frame(b)) << "a colour change while paused renders the view";
  EXPECT_TRUE(sceneColumns(a) != sceneColumns(b)) << "and the new colour shows";
  EXPECT_FALSE(frame(a));
  EXPECT_TRUE(a == b);

  // A turn of the wheel (zoom) is motion: draft; the next still frame is final, rendered anew.
  in.mouse_x = 100.0f;
  in.mouse_y = 180.0f;  // (the overlay's text is at the top and the bottom)
  in.wheel = 1.0f;
  EXPECT_TRUE(frame(a));
  EXPECT_TRUE(ui.renderer().stats().draft);
  EXPECT_TRUE(frame(a)) << "the first still frame after the motion is rendered";
  EXPECT_FALSE(ui.renderer().stats().draft) << "at final quality";
  EXPECT_FALSE(frame(b));
  EXPECT_TRUE(a == b);

  // A step moves the simulation: rendered.
  ui.sim().stepOnce();
  EXPECT_TRUE(frame(b));
  EXPECT_FALSE(frame(a));
  // The re-presented view is the view rendered anew.
  ui.setWindowSavings(false);
  EXPECT_TRUE(frame(b));
  EXPECT_TRUE(sceneColumns(a) == sceneColumns(b)) << "the re-presented view is the view rendered anew";
}

// The kept target (the window's back buffer when GLX_MESA_copy_sub_buffer presents it): only the
// view's columns or the panel's are drawn, and only when they changed; the frames are the plain
// path's to the byte. A final-quality scene, so that a still view is re-presented.
TEST(WindowSavings, AKeptTargetIsDrawnOnlyWhereTheFrameChanged) {
  const Scene scene = smallChain();
  PanelScript kept, plain;
  kept.playing = plain.playing = 5;
  {
    HeadlessUi ui(scene, 640, 360);
    ui.setWindowSavings(true, /*target_keeps=*/true);
    ui.panel().setReadoutRefresh(0.25);  // as the window: the playing figures do not change every frame
    kept.run(ui);
  }
  {
    HeadlessUi ui(scene, 640, 360);
    ui.panel().setReadoutRefresh(0.25);
    plain.run(ui);
  }
  ASSERT_EQ(kept.frames.size(), plain.frames.size());
  for (size_t i = 0; i < kept.frames.size(); ++i)
    EXPECT_TRUE(kept.frames[i] == plain.frames[i]) << "frame " << i << " differs with the kept target";
  int view_only = 0, panel_only = 0;
  for (const UiGl::Damage& d : kept.damage) {
    view_only += d.view && !d.panel;
    panel_only += d.panel && !d.view;
  }
  EXPECT_GT(view_only, 0) << "the view changed under a still panel (playing between refreshes)";
  EXPECT_GT(panel_only, 0) << "the panel changed over a still view (a hover, the pause)";
  for (size_t i : kept.still) EXPECT_FALSE(kept.damage[i].any()) << "frame " << i << ": nothing changed, nothing drawn";
  for (size_t i : kept.moved) EXPECT_TRUE(kept.damage[i].view && kept.damage[i].panel) << "frame " << i;
}

// A kept target's pixels are trusted until the compositor is told otherwise (an expose, a
// resize): an unchanged frame draws nothing, even over what someone else drew there, and after
// forgetTarget the frame is drawn whole again. The overlay is followed over a re-presented view.
TEST(WindowSavings, AKeptTargetIsDrawnWholeWhenForgottenAndFollowsTheOverlay) {
  HeadlessUi ui(smallChain(), 640, 360);
  ui.setWindowSavings(true, /*target_keeps=*/true);
  ui.sim().setRunning(false);
  UiInput in;
  std::vector<uint8_t> first, px;
  for (int i = 0; i < 3; ++i) ui.frame(in, &first);  // settled: the last of them changed nothing
  EXPECT_FALSE(ui.lastDamage().any());
  const auto scribble = [&] {
    glBindFramebuffer(GL_FRAMEBUFFER, ui.targetFbo());
    glDisable(GL_SCISSOR_TEST);
    glClearColor(1.0f, 0.0f, 1.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
  };
  scribble();
  ui.frame(in, &px);
  EXPECT_FALSE(ui.lastDamage().any());
  EXPECT_EQ(px[0], 255) << "nothing was drawn: the scribble stays";
  EXPECT_EQ(px[1], 0);
  ui.forgetTarget();
  ui.frame(in, &px);
  EXPECT_TRUE(ui.lastDamage().view && ui.lastDamage().panel);
  EXPECT_TRUE(px == first) << "forgotten: the frame is drawn whole";

  // The view's overlay changes over a still view (the playback speed, set while paused, shows in
  // its text; no simulation change, so the view is re-presented): the view's columns are drawn
  // again, as the frame drawn whole shows them.
  ui.sim().setSpeedIndex(ui.sim().speedIndex() - 1);
  ui.frame(in, &px);
  EXPECT_FALSE(ui.lastViewRendered());
  EXPECT_TRUE(ui.lastDamage().view);
  std::vector<uint8_t> whole;
  ui.forgetTarget();
  ui.frame(in, &whole);
  EXPECT_TRUE(px == whole) << "the overlay's new text shows over the re-presented view";
  EXPECT_TRUE(px != first);
}

// The panel's running figures (simulated time, readouts) are refreshed a few times a second while
// the scene plays, so a playing scene does not redraw the panel every frame; what the user does
// shows at once. No GL: the panel's draw data itself is compared frame to frame.
TEST(WindowSavings, PlayingFiguresRefreshAFewTimesASecondAndAStepShowsAtOnce) {
  PanelContext ctx;
  LiveSim sim(smallChain());
  sim.setStepBudgetMs(0.0);
  Panel panel(sim);
  panel.setReadoutRefresh(0.25);
  panel.setSectionOpen("Readouts", true);
  const PanelLayout layout;
  UiInput in;
  in.dt = 1.0 / 60.0;
  const auto frame = [&] {  // the panel's vertices (not the view's overlay, which shows the time live)
    feedInput(in);
    ImGui::NewFrame();
    panel.build(layout);
    ImGui::Render();
    std::vector<uint8_t> out;
    const ImDrawData* d = ImGui::GetDrawData();
    for (int i = 0; i < d->CmdListsCount; ++i) {
      const ImDrawList* l = d->CmdLists[i];
      if (l == ImGui::GetBackgroundDrawList()) continue;
      const auto* b = reinterpret_cast<const uint8_t*>(l->VtxBuffer.Data);
      out.insert(out.end(), b, b + size_t(l->VtxBuffer.Size) * sizeof(ImDrawVert));
    }
    return out;
  };
  for (int i = 0; i < 3; ++i) frame();
  std::vector<uint8_t> last = frame();
  int changed = 0;
  for (int i = 0; i < 60; ++i) {  // one second of playing
    std::vector<uint8_t> now = frame();
    changed += now != last;
    last = std::move(now);
  }
  EXPECT_GE(changed, 3) << "the figures move while the scene plays";
  EXPECT_LE(changed, 5) << "about 4 times a second, not every frame";

  in.keys_down = {ImGuiKey_Space};  // pause
  frame();
  in.keys_down.clear();
  frame();
  const std::vector<uint8_t> paused = frame();
  EXPECT_TRUE(frame() == paused) << "paused and still: the panel does not change";
  in.keys_down = {ImGuiKey_RightArrow};  // one step: seen by the panel after it is drawn
  frame();
  in.keys_down.clear();
  EXPECT_TRUE(frame() != paused) << "a step while paused shows on the next frame, not a refresh later";
}

}  // namespace
}  // namespace ponyhop

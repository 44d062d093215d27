// The artist's tuning panel: Dear ImGui widgets generated from the scene's reflect() lists
// (every parameter, grouped, with units, ranges, tooltips and a reset-to-default button), the
// playback controls, readouts and plots, presets, and the mouse in the scene view (orbit, pan,
// zoom, and pulling on a body with a spring).
//
// No GLFW and no GL here: the panel only builds ImGui frames. The window (app/window_app.cpp)
// feeds ImGui from GLFW; tests and `render --ui` feed it synthetic input (UiInput: display size,
// time step, mouse, keys), so a test can click and drag the panel exactly as a user would.
//
//   PanelContext ctx;                 // the ImGui context, style and font
//   LiveSim sim(scene);  Panel panel(sim);
//   feedInput(input);  ImGui::NewFrame();  panel.build(layout);  ImGui::Render();
//   Camera cam = panel.camera();      // what the scene view shows
#pragma once

#include <Eigen/Core>
#include <future>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "app/ui_sim.h"
#include "engine/camera.h"
#include "sim/goal_solve.h"

struct ImGuiContext;

namespace ponyhop {

// The ImGui context of one panel (style, font). One at a time per thread (ImGui's rule).
class PanelContext {
 public:
  explicit PanelContext(float font_px = 15.0f);
  ~PanelContext();
  PanelContext(const PanelContext&) = delete;
  PanelContext& operator=(const PanelContext&) = delete;

 private:
  ImGuiContext* ctx_ = nullptr;
};

// Synthetic input for one frame (headless use). Coordinates: pixels, origin top-left.
struct UiInput {
  float width = 1280, height = 720;            // display size, scene view + panel
  double dt = 1.0 / 60.0;                      // s since the previous frame
  float mouse_x = -1e6f, mouse_y = -1e6f;      // off-screen by default
  bool mouse_down[3] = {false, false, false};  // left, right, middle
  float wheel = 0.0f;                          // notches, + zooms in
  bool ctrl = false, shift = false;
  std::vector<int> keys_down;  // ImGuiKey_ values held during this frame (Space, Backspace...)
};
// Writes the input into ImGui's io (call before ImGui::NewFrame()).
void feedInput(const UiInput& in);

struct PanelLayout {
  int width = 1280, height = 720;  // the whole frame
  int panel_width = 400;           // at the right; the scene view is the rest
  int sceneWidth() const { return width - panel_width; }
};

// A widget's rectangle in the last frame (pixels), for tests driving the panel.
struct WidgetRect {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  float cx() const { return 0.5f * (x0 + x1); }
  float cy() const { return 0.5f * (y0 + y1); }
};

class Panel {
 public:
  static constexpr int kDefaultWidth = 440;

  explicit Panel(LiveSim& sim);

  // Builds one frame between ImGui::NewFrame() and ImGui::Render(): the panel at the right, the
  // scene view's mouse handling and overlay at the left, then applies the edits (LiveSim::applyEdits)
  // and advances playback by io.DeltaTime (unless advance is false: the caller steps the
  // simulation itself, as `render --ui` does to hit each video frame's time exactly).
  void build(const PanelLayout& layout, bool advance = true);

  // The camera of the scene view now: the scene's camera, or the free view once the mouse moved it.
  Camera camera() const { return camera_; }
  bool freeView() const { return free_view_; }

  // Where a widget was in the last frame: a field by its dotted key ("chain.links",
  // "physics.gravity"), its reset button as "reset:KEY", other controls by name ("run", "step",
  // "reset", "save", "load", "speed", "path"). nullopt when it was not drawn (section closed).
  std::optional<WidgetRect> widgetRect(const std::string& id) const;
  // Opens or closes a section ("Look", "Presets", "Ponytail: every field", "Physics", "Camera", ...)
  // from the next frame on. Artist scales are "look:length", "look:stiffness", ...; the shipped
  // presets' buttons "preset:NAME".
  void setSectionOpen(const std::string& title, bool open);

  // The path the Save/Load buttons use (defaults to the scene's file).
  std::string& presetPath() { return preset_path_; }
  // Wall time of the last scene render (ms), shown with the other stage timings.
  void setRenderMs(double ms);
  // The window's last compose and swap, and its whole frame (ms): the readouts show the frame rate
  // and where the frame's time goes.
  void setFrameMs(double compose_ms, double frame_ms);
  // How often the panel's running figures (simulated time, behind, the Readouts section) are
  // refreshed while the scene plays, in seconds of io.DeltaTime; 0 (the default): every frame.
  // The window refreshes them 4 times a second, as MuJoCo's viewer and Blender's status bar do,
  // so that a playing scene does not redraw the panel (UiGl::setPanelCache) on every frame. A
  // step, an edit, a reset or a run/pause shows at once.
  void setReadoutRefresh(double seconds) { readout_refresh_ = seconds; }
  // The last message shown under Presets (saved / loaded / why not).
  const std::string& presetMessage() const { return preset_message_; }

  LiveSim& sim() { return sim_; }
  // The Goals section's solve (docs/GOALS.md, "In the panel"): running in the background, and the
  // last message ("solving...", what it reached, or why not).
  bool solving() const { return solve_.valid(); }
  const std::string& solveStatus() const { return solve_status_; }

 private:
  friend class FieldWidgets;
  friend class SectionVisitor;
  void drawPlayback();
  void drawLook();
  void drawReadouts();
  struct ShownFigures {  // when a group of running figures was last taken from the simulation
    bool valid = false, running = false;
    uint64_t changes = 0;
    double since = 0.0;  // s of io.DeltaTime
    bool due(const LiveSim& sim, double period) const;
    void taken(const LiveSim& sim);
  };
  void drawPresets();
  void drawSections();
  void drawGoals();
  void pollSolve();
  void drawCameraTools();
  void handleKeys();
  void handleViewMouse(const PanelLayout& layout);
  void drawViewOverlay(const PanelLayout& layout);
  void updateCamera(const PanelLayout& layout, double dt);
  bool pick(float mx, float my, const PanelLayout& layout);
  Eigen::Vector3d rayDirection(float mx, float my, const PanelLayout& layout) const;
  void remember(const std::string& id);
  bool sectionHeader(const char* title, bool default_open);

  LiveSim& sim_;
  std::string preset_path_;
  std::string preset_message_;
  bool preset_error_ = false;
  std::map<std::string, WidgetRect> rects_;
  std::map<std::string, bool> pending_open_;
  double panel_ms_ = 0.0;

  // The running figures as the panel shows them (refreshShown).
  double readout_refresh_ = 0.0;
  ShownFigures shown_playback_, shown_readout_group_;
  bool shown_behind_ = false;
  double shown_time_ = 0.0, shown_rtf_ = 0.0;
  Readouts shown_readouts_;
  std::string shown_phase_, shown_contacts_;

  // The scene view's camera.
  Camera camera_;
  FollowCamera follow_;
  double last_cam_time_ = 0.0;
  bool free_view_ = false;
  double azimuth_ = 0.0, elevation_ = 0.0, distance_ = 1.0;  // rad, rad, m
  Eigen::Vector3d view_target_ =
      Eigen::Vector3d::Zero();  // free view: looked-at point (or offset from the followed body)
  enum class Drag { None, Orbit, Pan, Pull } drag_ = Drag::None;
  double grab_depth_ = 0.0;  // m along the view direction, of the grabbed point

  // The goal solve, run on a copy of the applied scene in a thread of its own (the window keeps
  // drawing); its outcome per goal and the goals it was for (an edit since makes them stale).
  std::future<GoalSolveReport> solve_;
  std::string solve_status_;
  std::vector<GoalOutcome> solved_outcomes_;
  std::vector<Goal> solved_goals_;
  std::chrono::steady_clock::time_point solve_started_;
};

}  // namespace ponyhop

// The simulation behind the tuning panel: the scene being edited, the runtime built from it,
// playback (run, pause, step, speed), live readouts, and the rules that decide how an edit
// reaches the running simulation. No GL and no ImGui here: tests drive it directly, the panel
// (app/panel.h) edits it, the window and `render --ui` draw it.
//
// How an edit is applied (docs/TUNING.md has the table):
//   live        camera, light, render, name, duration, chain.color, chain.hair.*: nothing to
//               rebuild; the next frame shows it (the chain's look is drawn from applied()).
//   keep state  every other parameter (gravity, dt, solver, masses, damping, stiffness, drag,
//               colours, hopper gains...): the runtime is rebuilt from the edited scene and the
//               running state is carried over: simulated time, and the pose and velocity of every
//               dynamic body. Needs the same bodies in the same order and joints that still close
//               (max joint error below 0.1 mm after the copy); otherwise it falls back to restart.
//   restart     what changes the bodies or the starting conditions (chain.links, chain.length,
//               chain.direction, chain.attach, anchor.*, head placement and animation, hopper
//               initial position/velocity, a section added or removed): rebuilt at t = 0.
// Every edit is validated (validateScene) first; an invalid edit is not applied and error() says
// why, naming the field and the allowed range.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "engine/renderer.h"
#include "engine/scene_draw.h"
#include "physics/models/perturbation.h"
#include "sim/scene.h"
#include "sim/sim.h"

namespace ponyhop {

// Playback rates: slow motion down to 1/16, fast forward up to 4x.
inline constexpr std::array<double, 9> kPlaybackSpeeds{1.0 / 16, 1.0 / 8, 1.0 / 4, 1.0 / 2, 1.0, 1.5, 2.0, 3.0, 4.0};
inline constexpr int kRealTimeSpeedIndex = 4;

// A fixed-size history of one readout, oldest first after `offset` (ImGui::PlotLines' layout).
class History {
 public:
  static constexpr int kSize = 240;
  void push(float v);
  const float* data() const { return values_.data(); }
  int offset() const { return next_; }
  int count() const { return kSize; }
  float last() const { return values_[static_cast<size_t>((next_ + kSize - 1) % kSize)]; }
  float minValue() const;
  float maxValue() const;
  void clear();

 private:
  std::array<float, kSize> values_{};
  int next_ = 0;
  int filled_ = 0;
};

// What the panel shows under "Readouts": one sample per displayed frame.
struct Readouts {
  History joint_error;    // m, largest joint separation
  History energy;         // J, kinetic + potential of the dynamic bodies
  History step_us;        // us, mean wall time of one physics step during the frame
  History hopper_height;  // m, body centre of mass above the ground
  History hopper_speed;   // m/s, horizontal speed of the body
  History rtf;            // achieved real-time factor (simulated s per wall s / requested speed)
  // Smoothed per-stage wall times of a displayed frame (ms).
  double physics_ms = 0.0, render_ms = 0.0, panel_ms = 0.0, frame_ms = 0.0;
  double compose_ms = 0.0;        // the window's compose (scene blit + panel) and swap
  double physics_frame_ms = 0.0;  // this frame's physics, not smoothed (the window's summary adds these up)
  // false: the panel shows no wall-clock figure (step time, frame times), so that two frames of
  // the same scene are the same picture (snapshot and sensitivity tests); true for people.
  bool show_wall_clock = true;
  // The scene view's last frame: draft while something moves, final when all is still; its passes (ms).
  bool view_draft = false;
  double shadow_ms = 0.0, main_ms = 0.0, aa_ms = 0.0;
  void clear();
};

enum class ApplyKind { None, Live, KeepState, Restart };
const char* applyKindName(ApplyKind k);

class LiveSim {
 public:
  // Builds the runtime. Throws InputError when the scene cannot be built.
  explicit LiveSim(const Scene& scene);
  ~LiveSim();
  LiveSim(const LiveSim&) = delete;
  LiveSim& operator=(const LiveSim&) = delete;

  // The working copy the panel edits; applyEdits() makes it the applied scene.
  Scene& edited() { return edited_; }
  const Scene& applied() const { return applied_; }
  // Applies edited() if it differs from applied(). Returns what was done; on an invalid edit
  // returns None and error() names the field (the simulation keeps the last good scene).
  ApplyKind applyEdits();
  ApplyKind lastApply() const { return last_apply_; }
  const std::string& error() const { return error_; }

  // Playback.
  void setRunning(bool on) { running_ = on; }
  bool running() const { return running_; }
  void setSpeedIndex(int i);
  int speedIndex() const { return speed_index_; }
  double speed() const { return kPlaybackSpeeds[static_cast<size_t>(speed_index_)]; }
  // Advances simulated time by wall_dt * speed when running (physics at its own dt, as many steps
  // as that takes; never more than `stepBudgetMs` of wall time per call when the budget is set,
  // the rest is dropped and the real-time factor shows it). Records the readouts.
  void advance(double wall_dt);
  // One physics step (paused or not).
  bool stepOnce();
  // Rebuilds applied() at t = 0: after a divergence, or to start over.
  void reset();
  // Wall-clock budget of advance() (ms); 0: none (deterministic: tests, headless rendering).
  void setStepBudgetMs(double ms) { step_budget_ms_ = ms; }
  // Steps until simulated time reaches t (no budget): `render --ui` and tests.
  bool advanceTo(double t);

  double simTime() const;
  bool ok() const { return runtime_->ok(); }
  // The stop message of a diverged run, with the simulated time (empty while ok()).
  std::string stopMessage() const;
  double achievedRealTimeFactor() const { return rtf_; }
  bool fallingBehind() const { return running_ && rtf_ < 0.95; }
  const Readouts& readouts() const { return readouts_; }
  Readouts& readouts() { return readouts_; }

  Sim& runtime() { return *runtime_; }
  const Sim& runtime() const { return *runtime_; }
  // The point the follow camera tracks: the body named by the applied camera.follow ("head",
  // "chain", "hopper"), else the head, the chain's anchor, or the origin.
  Eigen::Vector3d followPoint() const;
  // Number of chain links in the running world (0 without a chain).
  int linkCount() const;
  // The hopper's body, -1 when the scene has none; its controller's phase ("" without one).
  int hopperBody() const;
  std::string hopperPhase() const;

  // Mouse perturbation target (the panel picks and drags, the world's force element reads it).
  PerturbationTarget& perturbation() { return *perturbation_; }

  // Presets. save() writes edited() (validated first); load() replaces the scene (restart).
  // Both return false with error() set.
  bool save(const std::string& path);
  bool load(const std::string& path);

  // GL: uploads the runtime's meshes (once per runtime) and draws the current state, plus the
  // perturbation spring as a line.
  // Draft: the hair with its draft strand count (chain.hair.strands_draft), as the view moves.
  void draw(Renderer& renderer, bool draft = false);

  // How long the last rebuild took (ms): the panel shows it, so slow rebuilds are visible.
  double lastRebuildMs() const { return rebuild_ms_; }

  // Bumped by everything that can change what the scene view draws, other than the camera and
  // the view's size: an applied edit (live ones too: the light, the look), a rebuild, a reset, a
  // load, a step, playback that moved simulated time. The window re-presents its last final
  // picture while this, the camera and the size hold still (app/ui_headless.h, ViewReuse).
  uint64_t changes() const { return changes_; }

 private:
  void replaceRuntime(std::unique_ptr<Sim> next, double time_offset);
  ApplyKind classify(const Scene& from, const Scene& to) const;
  void record(double sim_advanced, double wall_dt, double step_us);

  Scene edited_;
  Scene applied_;
  std::unique_ptr<Sim> runtime_;
  double time_offset_ = 0.0;  // simulated time of the runtime's t = 0 (a keep-state rebuild)
  std::shared_ptr<PerturbationTarget> perturbation_ = std::make_shared<PerturbationTarget>();
  std::string error_;
  ApplyKind last_apply_ = ApplyKind::None;

  bool running_ = true;
  int speed_index_ = kRealTimeSpeedIndex;
  double step_budget_ms_ = 0.0;
  bool paused_by_stop_ = false;  // the run stopped itself (divergence): reset resumes it
  double target_time_ = 0.0;     // simulated time playback wants to reach
  double rtf_ = 1.0;
  Readouts readouts_;
  double rebuild_ms_ = 0.0;
  uint64_t changes_ = 0;

  // The running sim's meshes on the renderer (released when the sim is replaced).
  SceneDraw draw_;
};

// The dotted keys whose value differs between two scenes ("chain.links", "physics.gravity").
std::set<std::string> changedKeys(const Scene& a, const Scene& b);

}  // namespace ponyhop

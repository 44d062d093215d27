#include "app/ui_sim.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>

#include "engine/asset_loader.h"
#include "physics/stage_times.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

void flatten(const nlohmann::json& j, const std::string& prefix, std::map<std::string, nlohmann::json>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      flatten(it.value(), prefix.empty() ? it.key() : prefix + "." + it.key(), out);
  } else {
    out[prefix] = j;  // numbers, strings, vectors and key lists are compared whole
  }
}

bool startsWith(const std::string& s, const std::string& p) {
  return s.size() >= p.size() && s.compare(0, p.size(), p) == 0 && (s.size() == p.size() || s[p.size()] == '.');
}

// True when the only differences are in hopper.command.*.
bool onlyHopperCommand(const Scene& a, const Scene& b) {
  for (const std::string& k : changedKeys(a, b)) {
    if (!startsWith(k, "hopper.command")) return false;
  }
  return a.hopper.has_value() && b.hopper.has_value();
}

std::unique_ptr<Sim> makeSim(const Scene& scene) { return std::make_unique<Sim>(scene, &assimpAssets()); }

double smooth(double old_value, double sample) { return old_value <= 0.0 ? sample : 0.9 * old_value + 0.1 * sample; }

}  // namespace

// ---------------------------------------------------------------------------------------------

void History::push(float v) {
  values_[static_cast<size_t>(next_)] = v;
  next_ = (next_ + 1) % kSize;
  filled_ = std::min(filled_ + 1, kSize);
}

float History::minValue() const {
  if (filled_ == 0) return 0.0f;
  float m = last();
  for (int i = 0; i < filled_; ++i) m = std::min(m, values_[static_cast<size_t>((next_ + kSize - 1 - i) % kSize)]);
  return m;
}

float History::maxValue() const {
  if (filled_ == 0) return 0.0f;
  float m = last();
  for (int i = 0; i < filled_; ++i) m = std::max(m, values_[static_cast<size_t>((next_ + kSize - 1 - i) % kSize)]);
  return m;
}

void History::clear() {
  values_.fill(0.0f);
  next_ = filled_ = 0;
}

void Readouts::clear() {
  for (History* h : {&joint_error, &energy, &step_us, &hopper_height, &hopper_speed, &rtf}) h->clear();
}

const char* applyKindName(ApplyKind k) {
  switch (k) {
    case ApplyKind::None:
      return "none";
    case ApplyKind::Live:
      return "live";
    case ApplyKind::KeepState:
      return "rebuilt, state kept";
    case ApplyKind::Restart:
      return "rebuilt, restarted at t = 0";
  }
  return "";
}

std::set<std::string> changedKeys(const Scene& a, const Scene& b) {
  std::map<std::string, nlohmann::json> fa, fb;
  flatten(sceneToJson(a), "", fa);
  flatten(sceneToJson(b), "", fb);
  std::set<std::string> keys;
  for (const auto& [k, v] : fa) {
    auto it = fb.find(k);
    if (it == fb.end() || it->second != v) keys.insert(k);
  }
  for (const auto& [k, v] : fb) {
    if (!fa.count(k)) keys.insert(k);
  }
  return keys;
}

// ---------------------------------------------------------------------------------------------

LiveSim::LiveSim(const Scene& scene) : edited_(scene), applied_(scene) { replaceRuntime(makeSim(scene), 0.0); }

LiveSim::~LiveSim() = default;  // the renderer frees its meshes itself when it goes

void LiveSim::setSpeedIndex(int i) { speed_index_ = std::clamp(i, 0, static_cast<int>(kPlaybackSpeeds.size()) - 1); }

double LiveSim::simTime() const { return time_offset_ + runtime_->time(); }

std::string LiveSim::stopMessage() const {
  if (runtime_->ok()) return "";
  char buf[96];
  std::snprintf(buf, sizeof buf, "Stopped at simulated time %.4f s", simTime());
  std::string msg = std::string(buf) + (time_offset_ > 0.0 ? " (world time counts from the last rebuild)" : "") +
                    ":\n" + runtime_->status();
  return msg;
}

int LiveSim::linkCount() const {
  const Chain* c = runtime_->chain();
  return c ? static_cast<int>(c->links.size()) : 0;
}

Eigen::Vector3d LiveSim::followPoint() const {
  // The applied scene decides: a live camera edit does not rebuild the sim.
  return runtime_->followPoint(applied_.camera.follow);
}

int LiveSim::hopperBody() const {
  const Hopper* h = runtime_->hopper();
  return h && h->built() ? h->model().body : -1;
}

std::string LiveSim::hopperPhase() const {
  const Hopper* h = runtime_->hopper();
  return h && h->built() ? h->phaseName() : "";
}

ApplyKind LiveSim::classify(const Scene& from, const Scene& to) const {
  const std::set<std::string> keys = changedKeys(from, to);
  if (keys.empty()) return ApplyKind::None;
  if (from.head.has_value() != to.head.has_value() || from.chain.has_value() != to.chain.has_value() ||
      from.anchor.has_value() != to.anchor.has_value() || from.hopper.has_value() != to.hopper.has_value()) {
    return ApplyKind::Restart;
  }
  // Each field's metadata says how its edit applies (FieldMeta::apply, inherited from its section).
  Scene probe;
  bool live = true;
  for (const std::string& k : keys) {
    FieldMeta meta;
    const Apply apply = findField(probe, k, meta) ? meta.apply : Apply::KeepState;
    if (apply == Apply::Restart) return ApplyKind::Restart;
    live = live && apply == Apply::Live;
  }
  return live ? ApplyKind::Live : ApplyKind::KeepState;
}

void LiveSim::replaceRuntime(std::unique_ptr<Sim> next, double time_offset) {
  draw_.release();
  runtime_ = std::move(next);
  time_offset_ = time_offset;
  perturbation_->body = -1;  // body indices belong to the old world
  runtime_->world().addForceElement(std::make_unique<Perturbation>(perturbation_));
  target_time_ = simTime();
  ++changes_;
}

ApplyKind LiveSim::applyEdits() {
  edited_.path = applied_.path;  // relative mesh/clip paths resolve against the same file
  const ApplyKind kind = classify(applied_, edited_);
  if (kind == ApplyKind::None) {
    error_.clear();  // nothing pending: an earlier bad value was put back
    return ApplyKind::None;
  }
  try {
    validateScene(edited_, "panel");
  } catch (const InputError& e) {
    error_ = e.what();
    return ApplyKind::None;
  }
  ApplyKind done = kind;
  if (kind == ApplyKind::KeepState && onlyHopperCommand(applied_, edited_) && runtime_->hopper() && runtime_->ok()) {
    // A command (the velocity pad, height, heading) goes live without resetting the controller's
    // state machine, which a rebuild would do at every tick of a drag.
    if (Status s = runtime_->hopper()->setCommand(edited_.hopper->command); !s.ok()) {
      error_ = s.message();
      return ApplyKind::None;
    }
    done = ApplyKind::Live;
  } else if (kind != ApplyKind::Live) {
    const auto t0 = Clock::now();
    try {
      auto next = makeSim(edited_);
      const double t = simTime();
      if (kind == ApplyKind::KeepState && !(runtime_->ok() && next->carryStateFrom(*runtime_, t))) {
        done = ApplyKind::Restart;
        next = makeSim(edited_);  // the copy above touched it
      }
      replaceRuntime(std::move(next), done == ApplyKind::KeepState ? t : 0.0);
    } catch (const std::exception& e) {
      error_ = e.what();
      return ApplyKind::None;
    }
    rebuild_ms_ = msSince(t0);
  }
  applied_ = edited_;
  error_.clear();
  last_apply_ = done;
  ++changes_;
  return done;
}

void LiveSim::reset() {
  try {
    replaceRuntime(makeSim(applied_), 0.0);
  } catch (const std::exception& e) {
    error_ = e.what();  // the applied scene built before; only a vanished file gets here
    return;
  }
  if (paused_by_stop_) running_ = true;
  paused_by_stop_ = false;
  rtf_ = 1.0;
}

bool LiveSim::stepOnce() {
  const auto t0 = Clock::now();
  const bool ok_now = runtime_->step();
  ++changes_;
  target_time_ = simTime();
  record(0.0, 0.0, 1000.0 * msSince(t0));
  if (!ok_now) {
    paused_by_stop_ = running_;
    running_ = false;
  }
  return ok_now;
}

bool LiveSim::advanceTo(double t) {
  const double dt = applied_.physics.dt;
  const auto t0 = Clock::now();
  int steps = 0;
  while (runtime_->ok() && simTime() + 0.5 * dt <= t) {
    runtime_->step();
    ++steps;
  }
  if (steps) ++changes_;
  target_time_ = simTime();
  readouts_.physics_frame_ms = msSince(t0);
  readouts_.physics_ms = smooth(readouts_.physics_ms, readouts_.physics_frame_ms);
  record(0.0, 0.0, steps ? 1000.0 * msSince(t0) / steps : readouts_.step_us.last());
  return runtime_->ok();
}

void LiveSim::advance(double wall_dt) {
  // A very slow frame (a stall, a debugger, a minimized window) is not caught up on: at most
  // 0.1 s of wall time counts, the rest is dropped.
  const double wall_raw = std::isfinite(wall_dt) ? std::max(wall_dt, 0.0) : 0.0;
  wall_dt = std::min(wall_raw, 0.1);
  const auto t_start = Clock::now();
  if (!running_ || !runtime_->ok()) {
    target_time_ = simTime();
    readouts_.physics_frame_ms = 0.0;
    readouts_.physics_ms = smooth(readouts_.physics_ms, 0.0);
    record(0.0, 0.0, readouts_.step_us.last());
    return;
  }
  const double dt = applied_.physics.dt;
  target_time_ += wall_dt * speed();
  const double t_before = simTime();
  int steps = 0;
  bool out_of_time = false;
  while (runtime_->ok() && simTime() + 0.5 * dt <= target_time_) {
    runtime_->step();
    ++steps;
    if (step_budget_ms_ > 0.0 && msSince(t_start) > step_budget_ms_) {
      out_of_time = true;
      break;
    }
  }
  if (steps) ++changes_;
  if (out_of_time) target_time_ = simTime();  // behind: drop the backlog instead of spiralling
  const double physics_ms = msSince(t_start);
  readouts_.physics_frame_ms = physics_ms;
  readouts_.physics_ms = smooth(readouts_.physics_ms, physics_ms);
  // The real-time factor is measured against the true wall time, so slow frames show as "behind".
  record(simTime() - t_before, wall_raw, steps ? 1000.0 * physics_ms / steps : readouts_.step_us.last());
  if (!runtime_->ok()) {
    running_ = false;
    paused_by_stop_ = true;
  }
}

void LiveSim::record(double sim_advanced, double wall_dt, double step_us) {
  if (wall_dt > 0.0) {
    const double wanted = wall_dt * speed();
    rtf_ = 0.8 * rtf_ + 0.2 * std::min(sim_advanced / wanted, 10.0);
  }
  const World& w = runtime_->world();
  readouts_.joint_error.push(static_cast<float>(runtime_->maxJointError()));
  readouts_.energy.push(static_cast<float>(w.energy()));
  readouts_.step_us.push(static_cast<float>(step_us));
  readouts_.rtf.push(static_cast<float>(rtf_ * speed()));
  if (const int h = hopperBody(); h >= 0) {
    const RigidBody& b = w.body(h);
    readouts_.hopper_height.push(static_cast<float>(b.x.z()));
    readouts_.hopper_speed.push(static_cast<float>(b.v.head<2>().norm()));
  }
}

bool LiveSim::save(const std::string& path) {
  try {
    validateScene(edited_, "panel");
    saveScene(edited_, path);
  } catch (const InputError& e) {
    error_ = e.what();
    return false;
  }
  error_.clear();
  return true;
}

bool LiveSim::load(const std::string& path) {
  try {
    Scene s = loadScene(path);
    replaceRuntime(makeSim(s), 0.0);
    applied_ = edited_ = s;
  } catch (const std::exception& e) {
    error_ = e.what();
    return false;
  }
  error_.clear();
  last_apply_ = ApplyKind::Restart;
  readouts_.clear();
  return true;
}

void LiveSim::draw(Renderer& renderer, bool draft) {
  draw_.upload(*runtime_, renderer);
  draw_.setDraft(draft);
  draw_.draw(*runtime_, renderer, applied_);  // the look from the applied scene: chain.color/hair are live
  const PerturbationTarget& p = *perturbation_;
  if (p.active() && p.body < runtime_->world().bodyCount()) {
    const Eigen::Vector3d a = p.grabbedPoint(runtime_->world().body(p.body));
    renderer.drawLine(a, p.target, Eigen::Vector3f(0.95f, 0.25f, 0.15f));
    Material m;
    m.color = {0.95f, 0.25f, 0.15f};
    renderer.drawSphere(p.target, 0.006, m);
    renderer.drawSphere(a, 0.004, m);
  }
}

}  // namespace ponyhop

// Wall time spent in each stage of World::step() (measured in the program, as MuJoCo's
// mjData.timer is), so that the bench and the panel can show what each part of a scene costs: a
// chain without a controller or contacts pays nothing for those stages.
//
// Times are exclusive: a stage called from inside another (RK4 and RATTLE re-run the force
// stages at their stage times; featherstone's step calls them at every evaluation) is charged to
// itself and paused in its caller. Time outside every stage (step control, kinematic updates,
// state checks) is not charged to any stage: compare total() with the wall time of step().
// Cost: two steady_clock reads per stage call (~25-50 ns): 4-5 % of a 2 us tree step at N = 8
// (docs/bench/profile.md). setEnabled(false) leaves the clock unread (the calls are still
// counted): the scaling bench times its steps that way, as the peers' steps are timed.
// setSource(ThreadCpu, stages) charges the thread's CPU time instead of wall time, so that a stage
// can be set against a step timed on that clock (the collision bench: a preempted thread is
// charged nothing on either side of the ratio). Its reads cost a system call (~0.2-0.5 us), so
// it reads the clock for the stages named only: an unnamed stage inside a named one is charged
// to the named one, and the step's other stages pay nothing.
#pragma once

#include <time.h>

#include <array>
#include <chrono>
#include <string_view>

namespace ponyhop {

// The clock of every wall-time readout (stages, frames, the bench), a duration on it in seconds,
// and milliseconds since t0 on it.
using Clock = std::chrono::steady_clock;
inline double durationSeconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }
inline double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// s of CPU time this thread has used (getrusage's per-thread clock), for timings on a shared machine.
inline double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

enum class Stage { ExternalForces, Controller, JointForces, Integrate, Stabilize, Contact };

struct StageTimes {
  static constexpr int kCount = 6;
  // Column names for CSV and the panel, in Stage order.
  static constexpr std::array<std::string_view, kCount> names{"external_forces", "controller", "joint_forces",
                                                              "integrate",       "stabilize",  "contact"};
  std::array<double, kCount> seconds{};  // s, exclusive time (wall or thread CPU) accumulated per stage
  std::array<long, kCount> calls{};      // how often each stage ran

  double operator[](Stage s) const { return seconds[static_cast<int>(s)]; }
  double total() const {
    double t = 0.0;
    for (double s : seconds) t += s;
    return t;
  }
};

// Accumulates StageTimes. time(stage) returns a scope: the stage's clock runs until the scope
// ends, the caller's stage (if any) is paused meanwhile.
class StageClock {
 public:
  enum class Source { Wall, ThreadCpu };
  class Scope {
   public:
    Scope(StageClock* c, int previous) : clock_(c), previous_(previous) {}
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
    ~Scope() {
      if (clock_) clock_->end(previous_);
    }

   private:
    StageClock* clock_;  // null: the clock is off
    int previous_;
  };

  static constexpr unsigned kAllStages = (1u << StageTimes::kCount) - 1;
  static constexpr unsigned bit(Stage s) { return 1u << static_cast<int>(s); }

  [[nodiscard]] Scope time(Stage stage) {
    ++times_.calls[static_cast<int>(stage)];
    if (!enabled_ || !(stages_ & bit(stage))) return Scope(nullptr, -1);
    const int previous = active_;
    charge(now());
    active_ = static_cast<int>(stage);
    return Scope(this, previous);
  }
  const StageTimes& times() const { return times_; }
  void reset() { times_ = {}; }
  // Off: no clock reads, seconds stay as they are (calls are still counted). Only between steps
  // (a stage scope open across the switch would charge or end the wrong stage).
  void setEnabled(bool on) {
    enabled_ = on;
    active_ = -1;
  }
  // Wall time (the default) or the thread's CPU time, for the stages in the mask (bit(stage)
  // or'ed; the default all). Only between steps, as setEnabled.
  void setSource(Source s, unsigned stages = kAllStages) {
    source_ = s;
    stages_ = stages;
    active_ = -1;
  }

 private:
  double now() const {
    if (source_ == Source::ThreadCpu) return threadCpuSeconds();
    return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
  }
  void charge(double t) {
    if (active_ >= 0) times_.seconds[active_] += t - since_;
    since_ = t;
  }
  void end(int previous) {
    charge(now());
    active_ = previous;
  }

  StageTimes times_;
  int active_ = -1;
  bool enabled_ = true;
  Source source_ = Source::Wall;
  unsigned stages_ = kAllStages;  // the stages whose scopes read the clock
  double since_ = 0.0;            // s on the source's clock
};

}  // namespace ponyhop

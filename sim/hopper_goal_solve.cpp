#include "sim/hopper_goal_solve.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>

#include "physics/models/hopper.h"
#include "sim/goals.h"
#include "sim/input_error.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

double hopperSolveCpu() { return double(std::clock()) / CLOCKS_PER_SEC; }

const HopperParams& solvedHopper(const Scene& scene) {
  if (scene.hopper) return *scene.hopper;
  return scene.hoppers.front();
}

// The scene's own command at t (its script's last key at or before t, else its command).
HopperCommand sceneHopperCommand(const Scene& scene, double t) {
  const HopperParams& p = solvedHopper(scene);
  return courseCommandAt(p.script, t, p.command);
}

// The unknowns: changes (dvx, dvy, dheight) of the scene's own command at K keys, c[3 k + d], each
// from its key's time to the next; the last key time (T) ends them. c = 0 is the scene's own course.
struct Keys {
  const Scene* scene = nullptr;
  std::vector<double> times;  // K + 1: the last one ends the changes

  int count() const { return int(times.size()) - 1; }
  Eigen::Index size() const { return Eigen::Index(count()) * 3; }

  static constexpr double kLower[3] = {-5.0, -5.0, 0.5};  // the command's ranges (HopperCommand::reflect)
  static constexpr double kUpper[3] = {5.0, 5.0, 3.0};

  // The key whose change holds at t (-1: none).
  int keyAt(double t) const {
    if (t < times.front() - 1e-12 || t >= times.back() - 1e-12) return -1;
    int k = 0;
    while (k + 1 < count() && times[size_t(k) + 1] <= t + 1e-12) ++k;
    return k;
  }
  // The course: at every change time (the keys' and the scene script's), the scene's command there
  // plus the key's change, within the command's ranges. at_bound: the first command before
  // bound_before (s) that was cut to its range.
  std::vector<HopperCommandKey> script(const Eigen::VectorXd& c, std::string* at_bound = nullptr,
                                       double bound_before = INFINITY) const {
    std::vector<double> cuts(times.begin(), times.end());
    for (const HopperCommandKey& k : solvedHopper(*scene).script)
      if (k.t > 0.0) cuts.push_back(k.t);  // after T too: the scene's own course goes on
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
    std::vector<HopperCommandKey> s;
    for (double t : cuts) {
      const HopperCommand own = sceneHopperCommand(*scene, t);
      HopperCommandKey key{t, own.vx, own.vy, own.height, own.heading};
      const int k = keyAt(t);
      if (k >= 0) {
        double* v[3] = {&key.vx, &key.vy, &key.height};
        for (int d = 0; d < 3; ++d) {
          const double want = *v[d] + c(3 * k + d);
          *v[d] = std::clamp(want, kLower[d], kUpper[d]);
          if (at_bound && at_bound->empty() && *v[d] != want && t < bound_before) {
            static const char* names[3] = {"vx", "vy", "height"};
            char buf[160];
            std::snprintf(buf, sizeof buf, "the command %s from t = %.3g s is at its bound %g", names[d], t, *v[d]);
            *at_bound = buf;
          }
        }
      }
      s.push_back(key);
    }
    return s;
  }
  // The effort's metric: each key's span (s), the same for its three components (height in m
  // counts as a velocity in m/s: a scale of 1 s).
  Eigen::VectorXd weights() const {
    Eigen::VectorXd w(size());
    for (int k = 0; k < count(); ++k) w.segment<3>(3 * k).setConstant(times[size_t(k) + 1] - times[size_t(k)]);
    return w;
  }
};

// The power of the first hopper's muscles now (its leg spring with the thrust setpoint and stops,
// its hip servos: computeHopperForces on a copy of the bodies, kept in `bodies` from call to
// call), W.
double hopperMusclePower(const Sim& sim, std::vector<RigidBody>& bodies) {
  const Hopper* h = sim.hopper();
  bodies = sim.world().bodies();
  for (RigidBody& b : bodies) {
    b.force.setZero();
    b.torque.setZero();
  }
  computeHopperForces(h->model(), h->setpoints(), sim.time(), bodies);
  double p = 0.0;
  for (const RigidBody& b : bodies) p += b.force.dot(b.v) + b.torque.dot(b.w);
  return p;
}

// Runs of the hopper with a course: from the start for the goal errors (recording a snapshot at
// each key), from a key's snapshot for a Jacobian column (a key changes nothing before its time).
class HopperShooter {
 public:
  HopperShooter(const Scene& scene, const AssetLoader* assets, const Keys& keys)
      : sim_(scene, assets), start_(sim_.snapshot()), goals_(scene.goals), keys_(keys) {
    for (const Goal& g : goals_) times_.push_back(g.t);
    for (size_t g = 0; g < times_.size(); ++g) order_.push_back(g);
    targets_.resize(goals_.size());
    for (size_t g = 0; g < goals_.size(); ++g) targets_[g] = goals_[g].position;
    std::sort(order_.begin(), order_.end(), [&](size_t a, size_t b) { return times_[a] < times_[b]; });
  }

  // The goals' points for course c, run from key `from` (-1: the start); record: the key
  // snapshots are taken on the way (a run the next differences start from). False when the run
  // stopped or the hopper fell (its body below 0.3 m at a goal's time).
  bool run(const Eigen::VectorXd& c, int from, std::vector<Eigen::Vector3d>& points, bool record,
           double* work = nullptr, double* abs_work = nullptr) {
    ++runs_;
    if (from < 0) {
      sim_.restore(start_);
    } else {
      sim_.restore(snapshots_[size_t(from)]);
    }
    sim_.hopper()->setScript(keys_.script(c));
    const double dt = sim_.scene().physics.dt;
    const double start = sim_.time();
    if (record) snapshots_.resize(size_t(keys_.count()));
    size_t next_key = from < 0 ? 0 : size_t(from);
    bool fine = true;
    for (size_t g : order_) {
      if (times_[g] + 0.5 * dt < start) continue;  // before the snapshot: unchanged
      while (sim_.ok() && sim_.time() + 0.5 * dt <= times_[g]) {
        while (record && next_key < size_t(keys_.count()) && keys_.times[next_key] < sim_.time() + dt)
          snapshots_[next_key++] = sim_.snapshot();
        if (work) {
          const double P = hopperMusclePower(sim_, muscle_bodies_);
          *work += P * dt;
          *abs_work += std::abs(P) * dt;
        }
        sim_.step();
      }
      goalPointNow(sim_, goals_[g], points[g]);
      targets_[g] = goalTargetNow(sim_, goals_[g]);  // a head-frame goal rides on the keyframed head
      if (!sim_.ok() || sim_.world().body(sim_.hopper()->model().body).x.z() < 0.3) fine = false;
    }
    while (record && next_key < size_t(keys_.count())) snapshots_[next_key++] = sim_.snapshot();
    return fine;
  }
  int runs() const { return runs_; }
  const std::string& failure() const { return sim_.status(); }
  // Where goal g wants its point at its time (world, m): its position, or for frame "head" that
  // position carried by the head's keyframed pose then (no command moves the head, so every run
  // agrees; set by each run).
  const Eigen::Vector3d& target(size_t g) const { return targets_[g]; }

 private:
  Sim sim_;
  SimSnapshot start_;
  const std::vector<Goal> goals_;
  const Keys& keys_;
  std::vector<RigidBody> muscle_bodies_;  // hopperMusclePower()'s copy of the bodies
  std::vector<double> times_;
  std::vector<Eigen::Vector3d> targets_;  // per goal: target(g)
  std::vector<size_t> order_;
  std::vector<SimSnapshot> snapshots_;
  int runs_ = 0;
};

std::string hopperText(const char* f, double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

}  // namespace

double hopperCommandEffort(const Scene& scene, const std::vector<HopperCommandKey>& script, double until) {
  if (script.empty() || !(scene.hopper || !scene.hoppers.empty())) return 0.0;
  // Piecewise constant on both sides: integrate over the union of their change times.
  std::vector<double> cuts{0.0, until};
  for (const HopperCommandKey& k : script)
    if (k.t > 0.0 && k.t < until) cuts.push_back(k.t);
  for (const HopperCommandKey& k : solvedHopper(scene).script)
    if (k.t > 0.0 && k.t < until) cuts.push_back(k.t);
  std::sort(cuts.begin(), cuts.end());
  double e = 0.0;
  for (size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double a = cuts[i], b = cuts[i + 1];
    if (b <= a) continue;
    const HopperCommand own = sceneHopperCommand(scene, a);
    // Before the course's first key the scene's own command holds.
    const HopperCommand cmd = courseCommandAt(script, a, own);
    e += (b - a) * ((cmd.vx - own.vx) * (cmd.vx - own.vx) + (cmd.vy - own.vy) * (cmd.vy - own.vy) +
                    (cmd.height - own.height) * (cmd.height - own.height));
  }
  return e;
}

GoalSolveReport solveHopperGoals(const Scene& scene_in, const AssetLoader* assets, const HopperGoalSolveOptions& opt) {
  const double cpu0 = hopperSolveCpu();
  const std::string& src = scene_in.path;
  if (scene_in.goals.empty()) throw InputError(src + ": goals: the scene has no goals to solve for");
  if (!scene_in.hopper && scene_in.hoppers.empty())
    throw InputError(src + ": the hopper's goal solve steers a hopper, and the scene has none");
  for (size_t g = 0; g < scene_in.goals.size(); ++g) {
    GoalPoint p;
    std::string why;
    if (!parseGoalPoint(scene_in.goals[g].point, p, &why) ||
        (p.kind != GoalPoint::Kind::Toe && p.kind != GoalPoint::Kind::Body)) {
      throw InputError(src + ": goals." + std::to_string(g) + ".point: \"" + scene_in.goals[g].point +
                       "\": the hopper's solve takes toe or body goals only");
    }
  }
  if (opt.keys == 1 || opt.keys < 0) throw InputError(src + ": the hopper's goal solve needs at least 2 keys");
  double T = 0.0;
  for (const Goal& g : scene_in.goals) T = std::max(T, g.t);
  if (!(T > 0.0)) throw InputError(src + ": goals: the hopper's goals need a time after 0");
  // Windows: the goals' distinct times in order; window w runs from the previous goal time (0 for
  // the first) to its own, and its keys, uniform over it, meet its goals with every earlier key held
  // (a key changes nothing before its time, so the goals already met stay met). Keys: one per
  // 0.5 s of the window (at least one), or `keys` over [0, T] shared out by the windows' lengths.
  std::vector<double> goal_times;
  for (const Goal& g : scene_in.goals) goal_times.push_back(g.t);
  std::sort(goal_times.begin(), goal_times.end());
  goal_times.erase(std::unique(goal_times.begin(), goal_times.end()), goal_times.end());
  Keys keys;
  keys.scene = &scene_in;
  std::vector<int> window_first;  // per window: its first key (and one past the last window's keys)
  double previous = 0.0;
  for (double tw : goal_times) {
    const double len = tw - previous;
    if (len <= 0.0) continue;  // a goal at t = 0: no key can move it
    const int n = opt.keys > 0 ? std::max(1, int(std::lround(opt.keys * len / T)))
                               : std::max(1, int(std::ceil(len / 0.5 - 1e-9)));
    window_first.push_back(int(keys.times.size()));
    for (int i = 0; i < n; ++i) keys.times.push_back(previous + len * i / n);
    previous = tw;
  }
  window_first.push_back(int(keys.times.size()));
  keys.times.push_back(T);
  Scene scene = scene_in;
  if (scene.guide) scene.guide->script.clear();  // the solve starts from the scene's own commands
  HopperShooter shooter(scene, assets, keys);
  const size_t G = scene.goals.size();
  const Eigen::VectorXd c0 = Eigen::VectorXd::Zero(keys.size()), w = keys.weights();
  Eigen::VectorXd c = c0;
  std::vector<Eigen::Vector3d> points(G), trial_points(G);
  GoalSolveReport report;
  if (!shooter.run(c, -1, points, true))
    throw InputError(src + ": the hopper's run with its own commands stopped or fell: " + shooter.failure());

  // Residuals of the goals due by `until`, scaled by sqrt(weight) / tolerance: a goal is met when
  // its block is within 1 (later goals' rows are zero).
  double until = 0.0;
  const auto residual = [&](const std::vector<Eigen::Vector3d>& p) {
    Eigen::VectorXd r = Eigen::VectorXd::Zero(3 * Eigen::Index(G));
    for (size_t g = 0; g < G; ++g) {
      const Goal& goal = scene.goals[g];
      if (goal.t > until + 1e-12) continue;
      r.segment<3>(3 * Eigen::Index(g)) = std::sqrt(goal.weight) / goal.tolerance * (p[g] - shooter.target(g));
    }
    return r;
  };
  const auto allMet = [&](const std::vector<Eigen::Vector3d>& p) {
    for (size_t g = 0; g < G; ++g)
      if (scene.goals[g].t <= until + 1e-12 && (p[g] - shooter.target(g)).norm() > scene.goals[g].tolerance)
        return false;
    return true;
  };
  // The merit: the scaled goal error plus a small multiple of the effort, so that of the courses
  // that meet the goals the solve drifts toward the one closest to the scene's own.
  const double eps = 1e-3;
  const auto merit = [&](const Eigen::VectorXd& r, const Eigen::VectorXd& cc) {
    return r.squaredNorm() + eps * (cc - c0).cwiseProduct(w).dot(cc - c0);
  };
  // A change beyond the command's whole range can do nothing more.
  const auto clamp = [&](Eigen::VectorXd& cc) {
    for (Eigen::Index i = 0; i < cc.size(); ++i) {
      const double span = Keys::kUpper[i % 3] - Keys::kLower[i % 3];
      cc(i) = std::clamp(cc(i), -span, span);
    }
  };
  int fell = 0;  // trial courses in which the hopper fell (or the run stopped)
  std::vector<std::pair<double, std::string>> window_why;  // per window: its end and what stopped it
  char line[256];
  for (size_t win = 0; win + 1 < window_first.size(); ++win) {
    const int k0 = window_first[win], k1 = window_first[win + 1];
    const Eigen::Index j0 = 3 * Eigen::Index(k0), nj = 3 * Eigen::Index(k1 - k0);
    until = keys.times[size_t(k1)];
    Eigen::VectorXd r = residual(points);
    double phi = merit(r, c);
    double mu = 1e-3;
    int it = 0;
    bool stalled = false;
    for (; it < opt.max_iterations && !allMet(points); ++it) {
      // The window's Jacobian by forward differences from each key's snapshot (recorded by the last
      // accepted run).
      Eigen::MatrixXd J(r.size(), nj);
      for (Eigen::Index j = 0; j < nj; ++j) {
        const double step = (j0 + j) % 3 == 2 ? opt.fd_height : opt.fd_speed;
        Eigen::VectorXd cp = c;
        cp(j0 + j) += step;
        trial_points = points;
        if (!shooter.run(cp, int((j0 + j) / 3), trial_points, false)) {
          J.col(j).setZero();  // the hopper falls that way: no help from this direction
          continue;
        }
        J.col(j) = (residual(trial_points) - r) / step;
      }
      // Levenberg-Marquardt steps on the merit until one lowers it.
      const Eigen::VectorXd wj = w.segment(j0, nj);
      const Eigen::MatrixXd H = J.transpose() * J + Eigen::MatrixXd(eps * wj.asDiagonal());
      const Eigen::VectorXd grad = J.transpose() * r + eps * (c - c0).segment(j0, nj).cwiseProduct(wj);
      bool accepted = false;
      while (!accepted && mu < 1e8) {
        Eigen::MatrixXd A = H;
        A.diagonal() += mu * H.diagonal().cwiseMax(1e-9);
        Eigen::VectorXd ct = c;
        ct.segment(j0, nj) -= A.ldlt().solve(grad);
        clamp(ct);
        trial_points = points;
        const bool fine = shooter.run(ct, k0, trial_points, false);
        const double phit = merit(residual(trial_points), ct);
        if (!fine) ++fell;
        if (fine && phit < phi) {
          c = ct;
          accepted = true;
          mu = std::max(mu / 3.0, 1e-7);
        } else {
          mu *= 4.0;
        }
      }
      if (!accepted) {
        stalled = true;
        break;
      }
      shooter.run(c, k0, points, true);  // the accepted course, its snapshots for the next differences
      r = residual(points);
      phi = merit(r, c);
      ++report.iterations;
      double worst = 0.0;
      for (size_t g = 0; g < G; ++g)
        if (scene.goals[g].t <= until + 1e-12) worst = std::max(worst, (points[g] - shooter.target(g)).norm());
      std::snprintf(line, sizeof line,
                    "window to t = %.3g s, iteration %d: largest goal error %.1f mm, effort %.4g m^2/s, damping %.2g",
                    until, it + 1, worst * 1000.0, hopperCommandEffort(scene, keys.script(c), T), mu);
      report.log.push_back(line);
    }
    std::string why;
    if (!allMet(points)) {
      why = stalled ? "no change of the commands lowered the goal error further (a local minimum, or a hop the "
                      "controller cannot place there)"
                    : "the iteration limit (" + std::to_string(opt.max_iterations) + ") was reached";
      if (fell > 0) why += "; " + std::to_string(fell) + " of the courses tried made the hopper fall";
    }
    window_why.emplace_back(until, why);
  }
  until = T;
  // The muscles' work up to the last goal with the scene's own course and with the solved one: what
  // the guidance asks of the hopper beyond what it does anyway (report.energy, abs_energy).
  double own_work = 0.0, own_abs = 0.0, work = 0.0, abs_work = 0.0;
  shooter.run(c0, -1, trial_points, false, &own_work, &own_abs);
  shooter.run(c, -1, points, true, &work, &abs_work);  // every goal of the final course
  report.energy = work - own_work;
  report.abs_energy = abs_work - own_abs;
  report.simulations = shooter.runs();

  // The outcome of the final course, and what stopped a goal that is not met.
  report.guide = scene_in.guide.value_or(GuideParams{});
  report.guide.enabled = true;
  report.guide.script = c == c0 ? std::vector<HopperCommandKey>{} : keys.script(c);
  report.goals.resize(G);
  for (size_t g = 0; g < G; ++g) {
    GoalOutcome& o = report.goals[g];
    o.target = shooter.target(g);
    o.reached = points[g];
    o.error = (o.reached - o.target).norm();
    o.met = o.error <= scene.goals[g].tolerance;
    if (o.met) continue;
    o.why = "the closest the hopper's commands got is " + hopperText("%.1f mm", o.error * 1000.0) + ": ";
    std::string stop = "its time is 0: no command can move it";
    for (const auto& [end, why] : window_why) {
      if (scene.goals[g].t <= end + 1e-12) {
        stop = why;
        break;
      }
    }
    std::string bound;  // a command cut to its range before the goal's time
    (void)keys.script(c, &bound, scene.goals[g].t);
    o.why += bound.empty() ? stop : bound;
  }
  report.all_met = std::all_of(report.goals.begin(), report.goals.end(), [](const GoalOutcome& o) { return o.met; });
  report.effort = hopperCommandEffort(scene, report.guide.script, T);
  report.cpu_seconds = hopperSolveCpu() - cpu0;
  return report;
}

}  // namespace ponyhop

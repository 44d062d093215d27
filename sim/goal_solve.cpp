#include "sim/goal_solve.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>

#include "sim/hopper_goal_solve.h"
#include "sim/input_error.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

double cpuSeconds() { return double(std::clock()) / CLOCKS_PER_SEC; }

std::string mm(double metres) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2f mm", metres * 1000.0);
  return buf;
}

// The unknowns: K free knots per joint at times_[0..K-1] and one more knot at times_[K], fixed at
// zero. c[(j K + k) 3 + d] is component d of joint j's torque at knot k.
struct Layout {
  int joints = 0;
  int knots = 0;
  std::vector<double> times;  // K + 1

  Eigen::Index size() const { return Eigen::Index(joints) * knots * 3; }
  Eigen::Index index(int j, int k, int d) const { return (Eigen::Index(j) * knots + k) * 3 + d; }

  GuideParams guide(const Eigen::VectorXd& c) const {
    GuideParams g;
    for (int j = 0; j < joints; ++j) {
      for (int k = 0; k <= knots; ++k) {
        GuideKnot knot;
        knot.joint = j;
        knot.t = times[size_t(k)];
        if (k < knots) knot.torque = c.segment<3>(index(j, k, 0));
        g.knots.push_back(knot);
      }
    }
    return g;
  }

  // G_kl = integral of B_k(t) B_l(t) dt over the whole curve, for the free knots: the effort of
  // one torque component is c^T G c. Four Gauss-Legendre points per interval integrate the
  // product of two cubics exactly.
  Eigen::MatrixXd gram() const {
    static const double xs[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
    static const double ws[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(knots, knots);
    for (size_t i = 0; i + 1 < times.size(); ++i) {
      const double a = times[i], b = times[i + 1];
      for (int q = 0; q < 4; ++q) {
        const double t = 0.5 * (a + b) + 0.5 * (b - a) * xs[q];
        std::array<double, 4> w;
        const int interval = guideWeights(times, t, w);
        for (int p = 0; p < 4; ++p) {
          for (int s = 0; s < 4; ++s) {
            const int kp = interval - 1 + p, ks = interval - 1 + s;
            if (kp < 0 || ks < 0 || kp >= knots || ks >= knots) continue;
            G(kp, ks) += 0.5 * (b - a) * ws[q] * w[size_t(p)] * w[size_t(s)];
          }
        }
      }
    }
    return G;
  }
};

// The simulation run again and again from saved states: the whole clip for the goal errors, and
// from a knot's snapshot for a Jacobian column (a knot's torque acts from two knots earlier on).
class Shooter {
 public:
  Shooter(const Scene& scene, const AssetLoader* assets, std::vector<double> goal_times)
      : sim_(scene, assets), start_(sim_.snapshot()), goal_times_(std::move(goal_times)) {
    for (size_t g = 0; g < goal_times_.size(); ++g) order_.push_back(g);
    std::sort(order_.begin(), order_.end(), [&](size_t a, size_t b) { return goal_times_[a] < goal_times_[b]; });
  }

  Sim& sim() { return sim_; }

  // Runs with `guide` from the start, recording each goal's point (world) and the snapshots at
  // `knot_times` (the last step start at or before each). `energy`, `abs_energy`: the torques'
  // work and the integral of |power|, J (both or neither).
  void runWhole(const GuideParams& guide, const std::vector<double>& knot_times, std::vector<Eigen::Vector3d>& points,
                std::vector<Eigen::Vector3d>* targets = nullptr, double* energy = nullptr,
                double* abs_energy = nullptr) {
    sim_.restore(start_);
    if (sim_.guide()) sim_.guide()->set(guide);
    knot_times_ = knot_times;
    snapshots_.assign(knot_times.size(), {});
    recorded_at_.assign(goal_times_.size(), 0.0);
    anchors_.assign(goal_times_.size(), Eigen::Vector3d::Zero());
    points.assign(goal_times_.size(), Eigen::Vector3d::Zero());
    if (targets) targets->assign(goal_times_.size(), Eigen::Vector3d::Zero());
    size_t next_knot = 0;
    const double dt = sim_.scene().physics.dt;
    for (size_t g : order_) {
      while (sim_.ok() && sim_.time() + 0.5 * dt <= goal_times_[g]) {
        while (next_knot < knot_times.size() && knot_times[next_knot] < sim_.time() + dt)
          snapshots_[next_knot++] = sim_.snapshot();
        if (energy) {
          const double P = power();
          *energy += P * dt;
          *abs_energy += std::abs(P) * dt;
        }
        sim_.step();
      }
      recorded_at_[g] = sim_.time();
      points[g] = point(g);
      if (sim_.chain()) anchors_[g] = sim_.chain()->anchor(sim_.world());
      if (targets) (*targets)[g] = target(g);
    }
    while (next_knot < knot_times.size()) snapshots_[next_knot++] = sim_.snapshot();
    valid_ = knot_times.size();
    ++runs_;
  }

  // Runs with `guide` from knot `from`'s snapshot up to `until` (s): the goals recorded at or after
  // the snapshot and due by `until` are run again, the others keep `points`' values. record: the
  // knot snapshots passed on the way are taken again (a run of the control that the next
  // differences start from); those after `until` are then stale (validSnapshots()).
  void runFrom(size_t from, double until, const GuideParams& guide, std::vector<Eigen::Vector3d>& points, bool record) {
    sim_.restore(snapshots_[from]);
    sim_.guide()->set(guide);
    const double start = sim_.time();
    const double dt = sim_.scene().physics.dt;
    size_t next_knot = from;
    for (size_t g : order_) {
      if (goal_times_[g] > until) break;
      if (recorded_at_[g] < start) continue;
      while (sim_.ok() && sim_.time() + 0.5 * dt <= goal_times_[g]) {
        while (record && next_knot < knot_times_.size() && knot_times_[next_knot] < sim_.time() + dt)
          snapshots_[next_knot++] = sim_.snapshot();
        const size_t at = size_t(std::lround(sim_.time() / dt));
        sim_.step();
        traceStep(at, record);
      }
      points[g] = point(g);
    }
    if (record) valid_ = next_knot;
    ++runs_;
  }
  // The knot snapshots [0, validSnapshots()) are of the last recorded run.
  size_t validSnapshots() const { return valid_; }

  // The events of runFrom()'s steps, to tell whether a perturbed run took other step decisions
  // than the recorded one: per step, the substeps it took (a split at an impact or by the step
  // control) and the contacts active after it (a contact made or broken). A recorded run keeps
  // its steps' events; any other counts its steps whose events differ from the recorded ones
  // (eventChanges()) and the first one's time (firstEventChange(), s; infinity when none) since
  // the last resetEvents().
  void resetEvents() {
    event_changes_ = 0;
    first_event_change_ = std::numeric_limits<double>::infinity();
  }
  int eventChanges() const { return event_changes_; }
  double firstEventChange() const { return first_event_change_; }

  void setGoals(std::vector<Goal> goals) { goals_ = std::move(goals); }
  int runs() const { return runs_; }
  // The chain's anchor at goal g's time in the last whole run.
  const Eigen::Vector3d& anchor(size_t g) const { return anchors_[g]; }
  const std::string& failure() const { return sim_.status(); }

 private:
  void traceStep(size_t at, bool record) {
    const Collisions* contacts = sim_.collisions();
    const long event = long(sim_.world().lastSubsteps()) * 65536 + (contacts ? contacts->stats().active : 0);
    if (events_.size() <= at) events_.resize(at + 1, -1);
    if (record) {
      events_[at] = event;
    } else if (events_[at] >= 0 && events_[at] != event) {
      ++event_changes_;
      first_event_change_ = std::min(first_event_change_, double(at) * sim_.scene().physics.dt);
    }
  }
  // The world point of goal g now, and where it should be (sim/goals.h).
  Eigen::Vector3d point(size_t g) const {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    goalPointNow(sim_, goals_[g], p);  // the scene's goals are checked against its parts
    return p;
  }
  Eigen::Vector3d target(size_t g) const { return goalTargetNow(sim_, goals_[g]); }
  // The torques' power: sum_j tau_j . (w_link - w_parent), W.
  double power() {
    GuideTorques* guide = sim_.guide();
    const Chain* chain = sim_.chain();
    if (!guide || !chain) return 0.0;
    const World& w = sim_.world();
    double p = 0.0;
    for (size_t j = 0; j < chain->links.size(); ++j) {
      const int parent = j == 0 ? chain->parent : chain->links[j - 1];
      const Eigen::Vector3d w_parent = parent == kWorldBody ? Eigen::Vector3d::Zero() : w.body(parent).w;
      p += guide->torque(j, w.time()).dot(w.body(chain->links[j]).w - w_parent);
    }
    return p;
  }

  Sim sim_;
  SimSnapshot start_;
  std::vector<double> goal_times_;
  std::vector<size_t> order_;
  std::vector<double> knot_times_;
  std::vector<SimSnapshot> snapshots_;
  size_t valid_ = 0;
  std::vector<double> recorded_at_;
  std::vector<Eigen::Vector3d> anchors_;
  std::vector<Goal> goals_;
  int runs_ = 0;
  std::vector<long> events_;  // per step of the recorded runs: substeps * 65536 + active contacts
  int event_changes_ = 0;
  double first_event_change_ = std::numeric_limits<double>::infinity();
};

std::vector<GoalPoint> goalPoints(const Scene& scene) {
  std::vector<GoalPoint> out;
  for (const Goal& g : scene.goals) {
    GoalPoint p;
    parseGoalPoint(g.point, p);  // validated with the scene (checkGoals)
    out.push_back(p);
  }
  return out;
}

std::vector<double> goalTimes(const Scene& scene) {
  std::vector<double> t;
  for (const Goal& g : scene.goals) t.push_back(g.t);
  return t;
}

void fillOutcomes(const Scene& scene, const std::vector<Eigen::Vector3d>& points,
                  const std::vector<Eigen::Vector3d>& targets, std::vector<GoalOutcome>& out) {
  out.resize(scene.goals.size());
  for (size_t g = 0; g < scene.goals.size(); ++g) {
    out[g].target = targets[g];
    out[g].reached = points[g];
    out[g].error = (points[g] - targets[g]).norm();
    out[g].met = out[g].error <= scene.goals[g].tolerance;
  }
}

// d(goal points)/dc_i for the unknowns `columns` (indices into c) by differences: column i from a
// run with c_i + step, from the snapshot of the knot two before c_i's (where its torque starts to
// act) up to `until`; central: also c_i - step. `points`: the points at c from a run that took the
// knot snapshots. Rows 3g..3g+2: goal g (zero for the goals after `until`).
// *flipped (when given): per column, whether its runs took other step decisions (substeps or
// active contacts) than the run at c (Shooter::eventChanges()).
Eigen::MatrixXd differences(Shooter& shooter, const Layout& layout, const Eigen::VectorXd& c,
                            const std::vector<Eigen::Vector3d>& points, double step, bool central,
                            const std::vector<Eigen::Index>& columns, double until,
                            std::vector<bool>* flipped = nullptr) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(Eigen::Index(points.size()) * 3, Eigen::Index(columns.size()));
  std::vector<Eigen::Vector3d> plus, minus;
  shooter.resetEvents();
  if (flipped) flipped->assign(columns.size(), false);
  for (size_t col = 0; col < columns.size(); ++col) {
    const int changes = shooter.eventChanges();
    const Eigen::Index i = columns[col];
    const size_t from = size_t(std::max(int((i / 3) % layout.knots) - 2, 0));
    Eigen::VectorXd cp = c;
    cp[i] += step;
    plus = points;
    shooter.runFrom(from, until, layout.guide(cp), plus, false);
    if (central) {
      cp[i] = c[i] - step;
      minus = points;
      shooter.runFrom(from, until, layout.guide(cp), minus, false);
    }
    if (flipped) (*flipped)[col] = shooter.eventChanges() > changes;
    for (size_t g = 0; g < points.size(); ++g)
      J.block<3, 1>(Eigen::Index(g) * 3, Eigen::Index(col)) =
          central ? Eigen::Vector3d((plus[g] - minus[g]) / (2 * step)) : Eigen::Vector3d((plus[g] - points[g]) / step);
  }
  return J;
}

// The unknowns for `knots` knots per joint over [0, T], T the last goal's time, on the root-most
// `joints` joints (0: all).
Layout makeLayout(const Scene& scene, int knots, int joints = 0) {
  double T = 0.0;
  for (const Goal& g : scene.goals) T = std::max(T, g.t);
  if (T <= 0.0) throw InputError(scene.path + ": goals: every goal is at t = 0, where no control can act yet");
  Layout layout;
  layout.joints = joints > 0 ? std::min(joints, scene.chain->links) : scene.chain->links;
  layout.knots = knots;
  const double h = T / (knots - 1);
  for (int k = 0; k <= knots; ++k) layout.times.push_back(k * h);
  return layout;
}

}  // namespace

Eigen::MatrixXd goalJacobian(const Scene& scene_in, const AssetLoader* assets, int knots, const Eigen::VectorXd& c,
                             double step, bool central) {
  const Layout layout = makeLayout(scene_in, knots);
  if (c.size() != layout.size()) throw InputError("goalJacobian: c has the wrong size");
  Scene scene = scene_in;
  scene.guide = layout.guide(c);
  Shooter shooter(scene, assets, goalTimes(scene));
  shooter.setGoals(scene.goals);
  std::vector<Eigen::Vector3d> points;
  shooter.runWhole(*scene.guide, std::vector<double>(layout.times.begin(), layout.times.end() - 1), points);
  std::vector<Eigen::Index> all(size_t(layout.size()));
  for (size_t i = 0; i < all.size(); ++i) all[i] = Eigen::Index(i);
  return differences(shooter, layout, c, points, step, central, all, std::numeric_limits<double>::infinity());
}

GoalSolveReport evaluateGoals(const Scene& scene, const AssetLoader* assets) {
  const double cpu0 = cpuSeconds();
  GoalSolveReport report;
  if (scene.guide) report.guide = *scene.guide;
  Shooter shooter(scene, assets, goalTimes(scene));
  shooter.setGoals(scene.goals);
  std::vector<Eigen::Vector3d> points, targets;
  shooter.runWhole(report.guide, {}, points, &targets, &report.energy, &report.abs_energy);
  fillOutcomes(scene, points, targets, report.goals);
  report.all_met = std::all_of(report.goals.begin(), report.goals.end(), [](const GoalOutcome& g) { return g.met; });
  report.simulations = shooter.runs();
  // The effort of the guide as applied: the integral of sum_j |tau_j|^2 by the trapezoid rule at dt.
  if (Sim& sim = shooter.sim(); sim.guide()) {
    const double dt = scene.physics.dt;
    double end = 0.0;
    for (const GuideKnot& k : report.guide.knots) end = std::max(end, k.t);
    for (double t = 0.0; t <= end; t += dt)
      for (size_t j = 0; j < sim.guide()->joints(); ++j) report.effort += sim.guide()->torque(j, t).squaredNorm() * dt;
  }
  // The hopper's solved commands: their effort against the scene's own (sim/hopper_goal_solve.h).
  if (scene.guide && scene.guide->enabled && !scene.guide->script.empty()) {
    double until = 0.0;
    for (const Goal& g : scene.goals) until = std::max(until, g.t);
    report.effort += hopperCommandEffort(scene, scene.guide->script, until);
  }
  report.cpu_seconds = cpuSeconds() - cpu0;
  return report;
}

GoalSolveReport solveGoals(const Scene& scene_in, const AssetLoader* assets, const GoalSolveOptions& opt) {
  const double cpu0 = cpuSeconds();
  const std::string& src = scene_in.path;
  if (scene_in.goals.empty()) throw InputError(src + ": goals: the scene has no goals to solve for");
  // Goals on the hopper alone: its commands are solved for (sim/hopper_goal_solve.h).
  const bool hopper_only = std::all_of(scene_in.goals.begin(), scene_in.goals.end(), [](const Goal& g) {
    GoalPoint p;
    return parseGoalPoint(g.point, p) && (p.kind == GoalPoint::Kind::Toe || p.kind == GoalPoint::Kind::Body);
  });
  if (hopper_only && (scene_in.hopper || !scene_in.hoppers.empty())) {
    HopperGoalSolveOptions ho;
    ho.keys = opt.knots;
    ho.max_iterations = opt.max_iterations;
    return solveHopperGoals(scene_in, assets, ho);
  }
  if (!scene_in.chain) throw InputError(src + ": the goal solve guides a chain, and the scene has none");
  if (opt.knots == 1 || opt.knots < 0) throw InputError(src + ": the goal solve needs at least 2 knots per joint");

  // Automatic knots: four knot intervals per window (six knots over [0, T] without windows).
  double T = 0.0;
  for (const Goal& g : scene_in.goals) T = std::max(T, g.t);
  const int knots = opt.knots > 0    ? opt.knots
                    : opt.window > 0 ? std::max(int(std::ceil(4.0 * T / opt.window)) + 1, 2)
                                     : 6;
  const Layout layout = makeLayout(scene_in, knots, opt.joints);
  const std::vector<double> knot_times(layout.times.begin(), layout.times.end() - 1);

  Scene scene = scene_in;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(layout.size());
  scene.guide = layout.guide(c);
  GoalSolveReport report;
  Shooter shooter(scene, assets, goalTimes(scene));
  shooter.setGoals(scene.goals);
  const std::vector<GoalPoint> kinds = goalPoints(scene);

  std::vector<Eigen::Vector3d> points, targets;
  shooter.runWhole(scene.guide.value(), knot_times, points, &targets);
  if (!shooter.sim().ok()) throw InputError(src + ": the unguided run stopped: " + shooter.failure());
  fillOutcomes(scene, points, targets, report.goals);

  // Goals no torque can meet are said so and left out of the solve: a hopper point (the chain's
  // torques do not steer the hopper), a point beyond the chain's reach from the anchor at that
  // time (the anchor's path is the unguided one: exact on a kinematic head or anchor).
  std::vector<size_t> active;
  const ChainParams& ch = *scene.chain;
  for (size_t g = 0; g < scene.goals.size(); ++g) {
    GoalOutcome& out = report.goals[g];
    if (kinds[g].kind == GoalPoint::Kind::Toe || kinds[g].kind == GoalPoint::Kind::Body) {
      if (!out.met) out.why = "a hopper point: the chain's torques do not steer the hopper (not solved for)";
      continue;
    }
    const int last_link = kinds[g].kind == GoalPoint::Kind::Tip ? ch.links - 1 : kinds[g].link;
    const double reach = (last_link + 1) * ch.length;
    const double d = (out.target - shooter.anchor(g)).norm();
    if (d > reach) {
      char t[32];
      std::snprintf(t, sizeof(t), "%g", scene.goals[g].t);
      out.why = "beyond the chain's reach: at t = " + std::string(t) + " s the target is " + mm(d) +
                " from the anchor and the point is " + mm(reach) + " of chain from it (" +
                std::to_string(last_link + 1) + " links x " + mm(ch.length) + "); the closest any control gets is " +
                mm(d - reach);
      continue;
    }
    active.push_back(g);
  }
  char line[256];
  // The goals due by `until` (s), their errors in the last run.
  const auto errorsText = [&](const std::vector<GoalOutcome>& o, double until) {
    std::string s;
    for (size_t g = 0; g < o.size(); ++g) {
      if (scene.goals[g].t > until) continue;
      if (!s.empty()) s += ' ';
      s += mm(o[g].error);
    }
    return s;
  };
  const auto allMet = [&](const std::vector<size_t>& goals) {
    return std::all_of(goals.begin(), goals.end(), [&](size_t g) { return report.goals[g].met; });
  };
  const auto weightedError = [&](const std::vector<Eigen::Vector3d>& p, const std::vector<size_t>& goals) {
    double e = 0.0;
    for (size_t g : goals) e += scene.goals[g].weight * (p[g] - targets[g]).squaredNorm();
    return e;
  };

  const Eigen::MatrixXd Gk = layout.gram();
  const auto effort = [&](const Eigen::VectorXd& x) {
    double e = 0.0;
    for (int j = 0; j < layout.joints; ++j)
      for (int d = 0; d < 3; ++d) {
        Eigen::VectorXd v(layout.knots);
        for (int k = 0; k < layout.knots; ++k) v[k] = x[layout.index(j, k, d)];
        e += v.dot(Gk * v);
      }
    return e;
  };

  // The stages. Goal g's point depends only on the torques before its time t_g, so the goals are
  // met in time order, each by the knots whose torque acts within its window
  // [max(t_prev + dt, t_g - window), t_g) (t_prev: the previous goal's time), the earlier knots
  // frozen: a stage's runs start from the snapshot where its first knot starts to act, and no
  // stage moves an earlier goal. window 0: one stage, every knot and goal (single shooting). Goals
  // at the same time share a stage.
  struct GoalWindow {
    double until = 0.0;         // s, the stage's goal time
    double earliest = 0.0;      // s, the previous stage's goal time + dt (where a window may start)
    double lower = 0.0;         // s, the window's start
    std::vector<size_t> goals;  // active goals due at `until`
    std::vector<int> knots;     // the free knots (indices into layout.times)
    // The knots whose torque acts within [lower, until).
    void pickKnots(const Layout& layout) {
      knots.clear();
      for (int k = 0; k < layout.knots; ++k) {
        const double acts_from = layout.times[size_t(std::max(k - 2, 0))];
        if (acts_from >= lower && acts_from < until) knots.push_back(k);
      }
    }
  };
  std::vector<GoalWindow> stages;
  {
    std::vector<size_t> by_time = active;
    std::stable_sort(by_time.begin(), by_time.end(),
                     [&](size_t a, size_t b) { return scene.goals[a].t < scene.goals[b].t; });
    const double dt = scene.physics.dt;
    for (size_t g : by_time) {
      const double t = scene.goals[g].t;
      if (!stages.empty() && (opt.window <= 0.0 || t - stages.back().until < 0.5 * dt)) {
        stages.back().goals.push_back(g);
        stages.back().until = std::max(stages.back().until, t);
        continue;
      }
      GoalWindow s;
      s.until = t;
      s.goals = {g};
      s.earliest = stages.empty() ? 0.0 : stages.back().until + dt;
      s.lower = opt.window <= 0.0 ? -std::numeric_limits<double>::infinity() : std::max(s.earliest, t - opt.window);
      s.pickKnots(layout);
      stages.push_back(s);
    }
    if (opt.window <= 0.0 && !stages.empty()) {
      stages.front().knots.clear();
      for (int k = 0; k < layout.knots; ++k) stages.front().knots.push_back(k);
    }
  }

  // One stage by Gauss-Newton SQP over its free knots; true when it stalled (no step lowers its
  // goals' error).
  const auto solveStage = [&](const GoalWindow& st) {
    const Eigen::Index nf = Eigen::Index(st.knots.size());
    std::vector<Eigen::Index> columns;  // the free unknowns' indices in c, (j nf + f) 3 + d
    for (int j = 0; j < layout.joints; ++j)
      for (int k : st.knots)
        for (int d = 0; d < 3; ++d) columns.push_back(layout.index(j, k, d));
    const Eigen::Index n = Eigen::Index(columns.size());
    const size_t from = size_t(std::max(st.knots.front() - 2, 0));
    // The current control run up to the stage's goals from the last snapshot still valid, taking
    // the snapshots its differences and trials start from.
    shooter.runFrom(std::min(from, shooter.validSnapshots() - 1), st.until, layout.guide(c), points, true);
    fillOutcomes(scene, points, targets, report.goals);
    Eigen::MatrixXd Gf(nf, nf);  // the Gram matrix of the free knots
    for (Eigen::Index a = 0; a < nf; ++a)
      for (Eigen::Index b = 0; b < nf; ++b) Gf(a, b) = Gk(st.knots[size_t(a)], st.knots[size_t(b)]);
    const Eigen::LLT<Eigen::MatrixXd> Gllt(Gf);
    const Eigen::Index m = Eigen::Index(st.goals.size()) * 3;
    Eigen::MatrixXd Jall;      // d(points)/dx, all goals' rows, the free unknowns' columns
    bool differenced = false;  // Jall is from differences at the current c (not a Broyden update)
    double damping = -1.0;     // the trust region's (set at the first iteration)
    double damping_growth = 2.0;
    int iterations = 0;
    while (!allMet(st.goals) && iterations < opt.max_iterations) {
      ++iterations;
      ++report.iterations;
      // The Jacobian: forward differences, one partial run per unknown, the first time and after
      // a Broyden-updated one failed to give a step; otherwise the rank-one update below.
      if (Jall.size() == 0) {
        std::vector<bool> flipped;
        Jall = differences(shooter, layout, c, points, opt.fd_step, false, columns, st.until, &flipped);
        differenced = true;
        // What the step decisions do to the differences: a column whose run split a substep or
        // made or broke a contact where the nominal run did not reads the jump as a slope.
        int flips = 0;
        double flipped_norm = 0.0;
        for (size_t col = 0; col < flipped.size(); ++col) {
          if (!flipped[col]) continue;
          ++flips;
          for (size_t g : st.goals)
            flipped_norm += Jall.block<3, 1>(Eigen::Index(g) * 3, Eigen::Index(col)).squaredNorm();
        }
        double norm = 0.0;
        for (size_t g : st.goals) norm += Jall.middleRows<3>(Eigen::Index(g) * 3).squaredNorm();
        std::snprintf(line, sizeof(line),
                      "  Jacobian by differences (step %g N m): %d of %d columns' runs took other step decisions "
                      "(substeps or contacts) than the nominal run (from t = %.3f s), holding %.0f %% of |J|^2",
                      opt.fd_step, flips, int(n), flips ? shooter.firstEventChange() : st.until,
                      norm > 0.0 ? 100.0 * flipped_norm / norm : 0.0);
        report.log.push_back(line);
      }
      Eigen::VectorXd r(m);
      Eigen::MatrixXd J(m, n);
      for (size_t a = 0; a < st.goals.size(); ++a) {
        const double w = std::sqrt(scene.goals[st.goals[a]].weight);
        r.segment<3>(Eigen::Index(a) * 3) = w * (points[st.goals[a]] - targets[st.goals[a]]);
        J.middleRows<3>(Eigen::Index(a) * 3) = w * Jall.middleRows<3>(Eigen::Index(st.goals[a]) * 3);
      }
      // Least effort meeting the linearized goals r + J (x' - x) = 0, x the free knots, the others
      // (x_F) frozen: with the effort x'^T G_ff x' + 2 x'^T b, b = G_fF x_F (the free knots'
      // coupling to the frozen ones through the curve),
      //   x' = G_ff^-1 (J^T lambda - b),  (J G_ff^-1 J^T + mu I) lambda = J x - r + J G_ff^-1 b,
      // with a small mu (a penalty 1/mu on the goal error) so that goals no torque moves leave the
      // system solvable. G_ff is applied per joint and component.
      Eigen::MatrixXd Y(n, m);  // G_ff^-1 J^T
      Eigen::VectorXd z(n), x(n);
      for (int j = 0; j < layout.joints; ++j)
        for (int d = 0; d < 3; ++d) {
          Eigen::VectorXd v(layout.knots), vf(nf);
          for (int k = 0; k < layout.knots; ++k) v[k] = c[layout.index(j, k, d)];
          const Eigen::VectorXd Gv = Gk * v;
          Eigen::MatrixXd block(nf, m);
          Eigen::VectorXd b(nf);
          for (Eigen::Index f = 0; f < nf; ++f) {
            const Eigen::Index idx = (j * nf + f) * 3 + d;
            block.row(f) = J.col(idx).transpose();
            vf[f] = v[st.knots[size_t(f)]];
            b[f] = Gv[st.knots[size_t(f)]];
          }
          b -= Gf * vf;
          block = Gllt.solve(block);
          const Eigen::VectorXd zf = Gllt.solve(b);
          for (Eigen::Index f = 0; f < nf; ++f) {
            const Eigen::Index idx = (j * nf + f) * 3 + d;
            Y.row(idx) = block.row(f);
            z[idx] = zf[f];
            x[idx] = vf[f];
          }
        }
      Eigen::MatrixXd A = J * Y;
      const double e0 = weightedError(points, st.goals);
      // The trial step from the free knots x.
      Eigen::VectorXd step;
      if (opt.trust_region) {
        // Levenberg-Marquardt: the step that minimizes |r + J dx|^2 + damping dx^T G_ff dx,
        //   dx = -G_ff^-1 J^T (J G_ff^-1 J^T + damping I)^-1 r,
        // the Gauss-Newton step's least-effort direction cut short in proportion to how far the
        // linearization has been trusted (damping 0: the full step to the linearized goals).
        if (damping < 0.0) damping = opt.initial_damping * std::max(A.trace() / double(m), 1e-300);
        Eigen::MatrixXd Ad = A;
        Ad.diagonal().array() += damping;
        step = -Y * Ad.ldlt().solve(r);
      } else {
        const double mu = 1e-10 * std::max(A.trace() / double(m), 1e-300);
        A.diagonal().array() += mu;
        const Eigen::VectorXd lambda = A.ldlt().solve(J * x - r + J * z);
        step = Y * lambda - z - x;
      }
      // Trials: one for the trust region (a failure raises the damping for the next iteration),
      // halvings for the line search.
      double alpha = 1.0;
      bool accepted = false;
      std::vector<Eigen::Vector3d> trial = points;
      const int trials = opt.trust_region ? 1 : opt.max_line_halvings + 1;
      for (int half = 0; half < trials; ++half, alpha *= 0.5) {
        const Eigen::VectorXd xt = x + alpha * step;
        Eigen::VectorXd ct = c;
        for (Eigen::Index i = 0; i < n; ++i) ct[columns[size_t(i)]] = xt[i];
        shooter.runFrom(from, st.until, layout.guide(ct), trial, true);
        const double et = weightedError(trial, st.goals);
        const double predicted = (r + alpha * J * step).squaredNorm();
        // The gain ratio: the actual reduction of the goal error over the linearization's.
        const double rho = (e0 - et) / std::max(e0 - predicted, 1e-300);
        std::snprintf(line, sizeof(line),
                      "  trial step %g: goal error %.3g mm -> predicted %.3g mm, actual %.3g mm (gain ratio %.2f)%s",
                      alpha, std::sqrt(e0) * 1e3, std::sqrt(predicted) * 1e3, std::sqrt(et) * 1e3, rho,
                      opt.trust_region ? (", damping " + std::to_string(damping)).c_str() : "");
        report.log.push_back(line);
        if (shooter.sim().ok() && et < e0) {
          if (opt.trust_region) {
            // Nielsen's update: less damping the better the linearization predicted the step.
            damping *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
            damping_growth = 2.0;
          }
          if (opt.broyden) {
            // Broyden's update: J += (dp - J dx) dx^T / (dx^T dx), the secant through the step taken.
            const Eigen::VectorXd dx = xt - x;
            Eigen::VectorXd dp(Jall.rows());
            for (size_t g = 0; g < points.size(); ++g) dp.segment<3>(Eigen::Index(g) * 3) = trial[g] - points[g];
            Jall += (dp - Jall * dx) * dx.transpose() / dx.squaredNorm();
            differenced = false;
          } else {
            Jall.resize(0, 0);
          }
          c = ct;
          points = trial;
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        // The last trial moved the snapshots: run the accepted control again.
        shooter.runFrom(from, st.until, layout.guide(c), points, true);
        if (!differenced) {
          // An updated Jacobian that gives no step: differences again before damping more.
          Jall.resize(0, 0);
          report.log.push_back("iteration " + std::to_string(report.iterations) +
                               ": the updated Jacobian gives no step; differences again");
          continue;
        }
        if (opt.trust_region && damping < 1e8 * std::max(A.trace() / double(m), 1e-300)) {
          damping *= damping_growth;
          damping_growth *= 2.0;
          report.log.push_back("iteration " + std::to_string(report.iterations) + ": no lower error; damping " +
                               std::to_string(damping));
          continue;
        }
      }
      fillOutcomes(scene, points, targets, report.goals);
      std::snprintf(line, sizeof(line), "iteration %d: goal errors %s, effort %.4g N^2 m^2 s, step %g%s",
                    report.iterations, errorsText(report.goals, st.until).c_str(), effort(c), accepted ? alpha : 0.0,
                    accepted ? "" : " (no step lowers the goal error: stopped)");
      report.log.push_back(line);
      if (!accepted) return true;
    }
    return false;
  };

  std::snprintf(line, sizeof(line), "iteration 0: goal errors %s, effort 0",
                errorsText(report.goals, std::numeric_limits<double>::infinity()).c_str());
  report.log.push_back(line);
  std::vector<bool> stalled(scene.goals.size(), false);
  // The adaptive window: a goal its window did not meet (or a window without a knot) gets twice
  // the time before it (up to the previous goal), the progress kept: a goal far from where the
  // motion goes needs a longer lever than a near one, and the longer window is paid only where it
  // is needed. False when the window cannot grow.
  const auto widen = [&](GoalWindow& st) {
    if (!opt.adaptive_window || opt.window <= 0.0 || st.lower <= st.earliest) return false;
    st.lower = std::max(st.earliest, st.until - 2.0 * (st.until - st.lower));
    st.pickKnots(layout);
    std::snprintf(line, sizeof(line), "stage t = %g s: the window widened to %zu knots per joint from t = %g s",
                  st.until, st.knots.size(),
                  st.knots.empty() ? st.lower : layout.times[size_t(std::max(st.knots.front() - 2, 0))]);
    report.log.push_back(line);
    return true;
  };
  for (GoalWindow& st : stages) {
    while (st.knots.empty() && widen(st)) {
    }
    if (st.knots.empty()) {
      // A window shorter than the knot spacing: no torque acts in it.
      for (size_t g : st.goals) stalled[g] = true;
      report.log.push_back("stage t = " + std::to_string(st.until) + " s: no knot acts within the window");
      continue;
    }
    if (opt.window > 0.0) {
      std::snprintf(line, sizeof(line), "stage t = %g s: %zu goal(s), %zu knots per joint from t = %g s, %d unknowns",
                    st.until, st.goals.size(), st.knots.size(), layout.times[size_t(std::max(st.knots.front() - 2, 0))],
                    int(st.knots.size()) * layout.joints * 3);
      report.log.push_back(line);
    }
    bool stuck = solveStage(st);
    while (!allMet(st.goals) && widen(st)) stuck = solveStage(st);
    if (stuck)
      for (size_t g : st.goals) stalled[g] = true;
  }
  // Every goal in one run of the final control (the stages ran each only up to its own goals).
  shooter.runWhole(layout.guide(c), knot_times, points);
  fillOutcomes(scene, points, targets, report.goals);
  for (size_t g : active) {
    GoalOutcome& o = report.goals[g];
    if (o.met) continue;
    o.why = stalled[g] ? "the solve stalled at " + mm(o.error) +
                             ": no step lowers the goal error (a collision or joint limit in the way, or too little "
                             "time to get there)"
                       : "not met after " + std::to_string(opt.max_iterations) + " iterations: closest " + mm(o.error);
  }
  report.guide = layout.guide(c);
  report.effort = effort(c);
  // The injected energy of the final control: one more whole run.
  std::vector<Eigen::Vector3d> final_points;
  shooter.runWhole(report.guide, {}, final_points, nullptr, &report.energy, &report.abs_energy);
  report.all_met = std::all_of(report.goals.begin(), report.goals.end(), [](const GoalOutcome& g) { return g.met; });
  report.simulations += shooter.runs();
  report.cpu_seconds = cpuSeconds() - cpu0;
  return report;
}

namespace {

// The goal springs: F = -k (x - p) on each goal's point during its window, applied at the point
// (force and its moment on the link).
class GoalSprings final : public Controller {
 public:
  struct Spring {
    int body = -1;
    Eigen::Vector3d local = Eigen::Vector3d::Zero();  // the point in the body frame
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    bool head_frame = false;
    double from = 0.0, to = 0.0;  // s, active window
  };
  GoalSprings(std::vector<Spring> springs, double k, int head) : springs_(std::move(springs)), k_(k), head_(head) {}
  void applyForces(World& world, double t) override {
    for (const Spring& s : springs_) {
      if (t < s.from || t > s.to) continue;
      RigidBody& b = world.body(s.body);
      const Eigen::Vector3d p = b.pointToWorld(s.local);
      const Eigen::Vector3d f = -k_ * (p - target(world, s));
      b.force += f;
      b.torque += (p - b.x).cross(f);
    }
  }
  bool dependsOnVelocity() const override { return false; }
  // The springs' power on the chain now, W.
  double power(const World& world) const {
    double P = 0.0;
    for (const Spring& s : springs_) {
      if (world.time() < s.from || world.time() > s.to) continue;
      const RigidBody& b = world.body(s.body);
      const Eigen::Vector3d p = b.pointToWorld(s.local);
      P += (-k_ * (p - target(world, s))).dot(b.velocityAt(p));
    }
    return P;
  }

 private:
  Eigen::Vector3d target(const World& world, const Spring& s) const {
    return s.head_frame ? world.body(head_).pointToWorld(s.position) : s.position;
  }
  std::vector<Spring> springs_;
  double k_;
  int head_;
};

}  // namespace

namespace {

// The springs of `sim`'s scene's goals, in time order, added to `sim`.
std::shared_ptr<GoalSprings> attachGoalSprings(Sim& sim, double stiffness) {
  const Scene& scene = sim.scene();
  const Chain* chain = sim.chain();
  const std::vector<GoalPoint> kinds = goalPoints(scene);
  for (const GoalPoint& k : kinds) {
    if ((k.kind == GoalPoint::Kind::Tip || k.kind == GoalPoint::Kind::Link) && !chain)
      throw InputError(scene.path + ": the goal springs pull a chain, and the scene has none");
    if ((k.kind == GoalPoint::Kind::Toe || k.kind == GoalPoint::Kind::Body) && !sim.hopper())
      throw InputError(scene.path + ": the goal springs pull a hopper, and the scene has none");
  }
  std::vector<size_t> order(scene.goals.size());
  for (size_t g = 0; g < order.size(); ++g) order[g] = g;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return scene.goals[a].t < scene.goals[b].t; });
  std::vector<GoalSprings::Spring> springs;
  double from = 0.0;
  for (size_t g : order) {
    const Goal& goal = scene.goals[g];
    if (kinds[g].kind == GoalPoint::Kind::Toe || kinds[g].kind == GoalPoint::Kind::Body) {
      // The hopper's toe (the foot's point that touches the ground, fixed in the foot where it is at
      // t = 0) or its body's centre.
      const Hopper* h = sim.hopper();
      const World& w = sim.world();
      const bool toe = kinds[g].kind == GoalPoint::Kind::Toe;
      const int body = toe ? h->model().foot : h->model().body;
      const Eigen::Vector3d local =
          toe ? Eigen::Vector3d(w.body(body).q.conjugate() * (h->footPoint(w) - w.body(body).x))
              : Eigen::Vector3d::Zero();
      springs.push_back({body, local, goal.position, goal.frame == GoalFrame::Head, from, goal.t});
      from = goal.t;
      continue;
    }
    const int link = kinds[g].kind == GoalPoint::Kind::Tip ? int(chain->links.size()) - 1 : kinds[g].link;
    springs.push_back({chain->links[size_t(link)], Eigen::Vector3d(0.0, 0.0, -0.5 * chain->length), goal.position,
                       goal.frame == GoalFrame::Head, from, goal.t});
    from = goal.t;
  }
  auto ctl = std::make_shared<GoalSprings>(springs, stiffness, sim.headBody());
  sim.world().addController(ctl);
  return ctl;
}

}  // namespace

void addGoalSprings(Sim& sim, double stiffness) { attachGoalSprings(sim, stiffness); }

SpringOutcome springGoals(const Scene& scene_in, const AssetLoader* assets, double stiffness) {
  Scene scene = scene_in;
  scene.guide.reset();
  Sim sim(scene, assets);
  const std::shared_ptr<GoalSprings> ctl = attachGoalSprings(sim, stiffness);
  std::vector<size_t> order(scene.goals.size());
  for (size_t g = 0; g < order.size(); ++g) order[g] = g;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return scene.goals[a].t < scene.goals[b].t; });
  SpringOutcome out;
  out.stiffness = stiffness;
  out.goals.resize(scene.goals.size());
  const double dt = scene.physics.dt;
  for (size_t g : order) {
    while (sim.ok() && sim.time() + 0.5 * dt <= scene.goals[g].t) {
      const double P = ctl->power(sim.world());
      out.work += P * dt;
      out.abs_work += std::abs(P) * dt;
      sim.step();
    }
    GoalOutcome& o = out.goals[g];
    const Goal& goal = scene.goals[g];
    o.target = goalTargetNow(sim, goal);
    goalPointNow(sim, goal, o.reached);
    o.error = (o.reached - o.target).norm();
    o.met = o.error <= goal.tolerance;
    if (!sim.ok()) o.why = "the simulation stopped: " + sim.status();
  }
  out.all_met = std::all_of(out.goals.begin(), out.goals.end(), [](const GoalOutcome& g) { return g.met; });
  return out;
}

SpringOutcome weakestGoalSpring(const Scene& scene, const AssetLoader* assets) {
  double lo = 0.0, hi = 1e-3;
  SpringOutcome best = springGoals(scene, assets, hi);
  while (!best.all_met && hi < 1e6) {
    lo = hi;
    hi *= 4.0;
    best = springGoals(scene, assets, hi);
  }
  if (!best.all_met) return best;
  while (lo > 0.0 && hi / lo > 1.02) {
    const double mid = std::sqrt(lo * hi);
    SpringOutcome o = springGoals(scene, assets, mid);
    if (o.all_met) {
      hi = mid;
      best = o;
    } else {
      lo = mid;
    }
  }
  return best;
}

}  // namespace ponyhop

#include "bench/bench_loops.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

#include "bench/bench_peers.h"
#include "bench/bench_report.h"
#include "bench/bench_run.h"
#include "engine/asset_loader.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

// One run of a loop scene: the closure error (every joint's error, max over every step), the
// energy drift against t = 0 (World::energy), the CPU seconds of Sim::step per simulated second.
struct LoopRun {
  double closure = 0.0;
  double drift = 0.0, e0 = 0.0;
  double cpu = std::numeric_limits<double>::infinity();  // least of the repeats
  std::string stopped;
};

std::unique_ptr<Sim> loopSim(const std::string& scene, const Method& m, double dt, std::vector<Override> extra,
                             bool keep_joints = true) {
  std::vector<Override> o = methodOverrides(m, dt);
  o.insert(o.end(), extra.begin(), extra.end());
  Scene s = loadScene(scene, o);
  if (!keep_joints) s.joints.clear();
  return std::make_unique<Sim>(s, &assimpAssets());
}

void runOnce(Sim& sim, double dt, double seconds, bool record, LoopRun& run) {
  const long steps = std::lround(seconds / dt);
  if (record) run.e0 = sim.world().energy();
  double cpu = 0.0;
  long done = 0;
  for (; done < steps && sim.ok(); ++done) {
    const double c0 = threadCpuSeconds();
    sim.step();
    cpu += threadCpuSeconds() - c0;
    if (!record) continue;
    run.closure = std::max(run.closure, sim.maxJointError());
    run.drift = std::max(run.drift, std::abs(sim.world().energy() - run.e0));
  }
  if (!sim.ok()) run.stopped = sim.status();
  if (done > 0) run.cpu = std::min(run.cpu, cpu / (static_cast<double>(done) * dt));
}

std::vector<Method> loopMethods() {
  std::vector<Method> m;
  for (const char* solver : {"dense", "tree", "featherstone"}) {
    for (const char* st : {"projection", "baumgarte", "none"}) m.push_back({solver, "rk4", st});
    if (std::string(solver) != "featherstone") m.push_back({solver, "rattle", "none"});
  }
  return m;
}

// Runs every method at every dt on a scene, interleaving the repeats of each dt's methods. A run
// that stops (a loop left without drift control opening, an explicit step past its stability limit
// at 1/60 s) is that row's finding, written with its reason, not a failure of the bench.
using LoopRuns = std::map<std::pair<std::string, int>, LoopRun>;  // by method name and 1/dt

LoopRuns closureTable(std::ofstream& md, const std::string& title, const std::string& scene,
                      const std::vector<Override>& extra, double seconds, bool energy, const LoopBenchOptions& o) {
  LoopRuns all;
  md << "\n## " << title << "\n\n"
     << "`" << scene << "`" << (extra.empty() ? "" : " with") <<
      [&] {
        std::string s;
        for (const Override& x : extra) s += " `" + x.key + "=" + x.value + "`";
        return s;
      }()
     << ", " << fmt(seconds, "%g") << " s at fixed steps (no automatic substeps). Closure: the largest joint error "
     << "of any step (m; a hinge's axis rows count as the sine of their angle). "
     << (energy ? "Energy drift: max |E - E0| over the run, and over |E0| (E0 against the chain's hanging reference). "
                : "Energy: not conserved (the head drives the loop; damping and drag). ")
     << "Cost: CPU seconds of Sim::step per simulated second, the least of " << o.repeats << " runs.\n\n"
     << "| method | dt | closure (m) | energy drift (J) | drift / E0 | CPU s per sim. s |\n|---|---|---|---|---|---|\n";
  for (int d : o.dts) {
    const double dt = 1.0 / d;
    std::vector<Method> methods = loopMethods();
    std::vector<LoopRun> runs(methods.size());
    for (int r = 0; r < o.repeats; ++r) {
      for (size_t k = 0; k < methods.size(); ++k) {
        auto sim = loopSim(scene, methods[k], dt, extra);
        runOnce(*sim, dt, seconds, r == 0, runs[k]);
      }
    }
    for (size_t k = 0; k < methods.size(); ++k) {
      const LoopRun& run = runs[k];
      md << "| " << methods[k].name() << " | 1/" << d << " | " << fmt(run.closure) << " | "
         << (energy ? fmt(run.drift) : std::string("-")) << " | "
         << (energy ? fmt(100.0 * run.drift / std::abs(run.e0), "%.2g") + " %" : std::string("-")) << " | "
         << fmt(run.cpu) << " |";
      if (!run.stopped.empty()) md << " stopped: " << run.stopped;
      md << "\n";
      std::fprintf(stderr, "bench loops: %s %-28s 1/%-5d closure %.3g m, drift %.3g J, %.3g cpu s/s%s\n", title.c_str(),
                   methods[k].name().c_str(), d, run.closure, run.drift, run.cpu,
                   run.stopped.empty() ? "" : " (stopped)");
      all[{methods[k].name(), d}] = run;
    }
    md.flush();
  }
  return all;
}

// One peer's run of the four-bar, measured as runOnce() measures ours: the largest gap of its four
// joints over every step, the energy drift against its own t = 0 energy, CPU per simulated second.
void peerOnce(const Peer& peer, const PeerFourBar& f, double dt, double seconds, bool record, LoopRun& run) {
  std::string error;
  auto sim = peer.makeFourBar(f, dt, error);
  if (!sim) {
    run.stopped = error;
    return;
  }
  std::vector<PeerLink> links;
  if (record) run.e0 = sim->energy();
  const long steps = std::lround(seconds / dt);
  double cpu = 0.0;
  long done = 0;
  for (; done < steps; ++done) {
    const double c0 = threadCpuSeconds();
    sim->step();
    cpu += threadCpuSeconds() - c0;
    if (!sim->finite()) {
      run.stopped = "t = " + fmt(sim->time(), "%.6g") + " s: the state became non-finite or ran away";
      break;
    }
    if (!record) continue;
    sim->links(links);
    run.closure = std::max(run.closure, f.jointError(links));
    run.drift = std::max(run.drift, std::abs(sim->energy() - run.e0));
  }
  if (done > 0) run.cpu = std::min(run.cpu, cpu / (static_cast<double>(done) * dt));
}

// The peers on the same four-bar beside ours (issue 34): each dt, each peer's repeats interleaved.
void peerTable(std::ofstream& md, const std::vector<Override>& extra, const LoopRuns& ours, const LoopBenchOptions& o) {
  const PeerModules modules = loadPeerModules(o.peer_dirs);
  const PeerFourBar f = peerFourBarOf(Sim(loadScene(o.four_bar, extra), &assimpAssets()));
  md << "\n## The peers on the same four-bar\n\n"
     << "The four-bar of the first table (servo off, the same geometry, masses, inertias, gravity, t = 0 pose and "
     << "dt, " << fmt(o.four_bar_seconds, "%g") << " s) in each peer engine, built as two trees (crank on a hinge with "
     << "the coupler on a ball joint; the follower on a hinge) closed by the engine's own point-to-point "
     << "constraint at the coupler's bottom end (bench/peer.h, PeerFourBar; ours closes the same RSSR linkage at "
     << "the follower's ground hinge). Closure: the largest gap of any of the four joints over every step (m; in "
     << "the engines with reduced coordinates, the closure's). Energy drift against the engine's own energy at "
     << "t = 0, over our |E0|. Cost: CPU seconds of the engine's step per simulated second, the least of " << o.repeats
     << " runs. Our rows are the first table's.\n\n";
  for (const std::string& note : modules.notes) md << "- " << note << "\n";
  for (const Peer& p : modules.peers) {
    if (p.makeFourBar) md << "- " << p.name << ": " << p.four_bar_version << "\n";
  }
  md << "\n| method | dt | closure (m) | energy drift (J) | drift / E0 | CPU s per sim. s "
        "|\n|---|---|---|---|---|---|\n";
  for (int d : o.dts) {
    const double dt = 1.0 / d;
    std::vector<LoopRun> runs(modules.peers.size());
    for (int r = 0; r < o.repeats; ++r) {
      for (size_t k = 0; k < modules.peers.size(); ++k) {
        if (modules.peers[k].makeFourBar) peerOnce(modules.peers[k], f, dt, o.four_bar_seconds, r == 0, runs[k]);
      }
    }
    const auto row = [&](const std::string& name, const LoopRun& run) {
      md << "| " << name << " | 1/" << d << " | " << fmt(run.closure) << " | " << fmt(run.drift) << " | "
         << fmt(100.0 * run.drift / std::abs(ours.begin()->second.e0), "%.2g") << " % | " << fmt(run.cpu) << " |";
      if (!run.stopped.empty()) md << " stopped: " << run.stopped;
      md << "\n";
      std::fprintf(stderr, "bench loops: four-bar %-28s 1/%-5d closure %.3g m, drift %.3g J, %.3g cpu s/s%s\n",
                   name.c_str(), d, run.closure, run.drift, run.cpu, run.stopped.empty() ? "" : " (stopped)");
    };
    for (const char* m : {"featherstone/rk4/projection", "featherstone/rk4/none", "dense/rattle/none"}) {
      if (auto it = ours.find({m, d}); it != ours.end()) row(std::string("ours: ") + m, it->second);
    }
    for (size_t k = 0; k < modules.peers.size(); ++k) {
      if (modules.peers[k].makeFourBar) row(modules.peers[k].name, runs[k]);
    }
    md.flush();
  }
}

}  // namespace

int runLoopBench(const LoopBenchOptions& o) {
  std::filesystem::create_directories(o.out);
  const std::string path = o.out + "/loops.md";
  std::ofstream md(path);
  if (!md) throw std::runtime_error(path + ": cannot write the file");
  md << "# Closed loops: closure, energy, cost, agreement\n\n"
     << "Written by `" << o.command_line << "` (bench/bench_loops.cpp; the method: docs/SOLVERS.md, \"Closed "
     << "loops\").\n\nLoad average before: " << loadAverage() << ".\n";
  int status = 0;
  const std::vector<Override> servo_off{{"chain.servo.stiffness", "0"}, {"chain.servo.damping", "0"}};
  const LoopRuns four_bar =
      closureTable(md, "The four-bar, its servo off (a conservative linkage swinging under gravity)", o.four_bar,
                   servo_off, o.four_bar_seconds, true, o);
  if (o.peers) peerTable(md, servo_off, four_bar, o);
  closureTable(md, "The hair loop (the braid tied back to the nape, on the showcase clip)", o.hair_loop, {},
               o.hair_loop_seconds, false, o);

  // Featherstone with the loop against the same tree without it: the hair loop with and without
  // its tie, rk4 + projection at 1/240 s, interleaved.
  {
    const double dt = 1.0 / 240.0;
    const Method m{"featherstone", "rk4", "projection"};
    LoopRun with, without;
    for (int r = 0; r < o.repeats; ++r) {
      for (auto [run, keep] : {std::pair{&with, true}, std::pair{&without, false}}) {
        auto sim = loopSim(o.hair_loop, m, dt, {}, keep);
        runOnce(*sim, dt, o.hair_loop_seconds, r == 0, *run);
        if (!run->stopped.empty()) status = 1;
      }
    }
    md << "\n## The cost of a loop in reduced coordinates\n\n"
       << "The hair loop with its tie and the same tree without it (`joints` emptied), " << m.name() << " at 1/240 s, "
       << fmt(o.hair_loop_seconds, "%g") << " s, CPU seconds per simulated second, the least of " << o.repeats
       << " interleaved runs each. Goal: at most 1.5x.\n\n"
       << "| tree | with the loop | loop / tree |\n|---|---|---|\n"
       << "| " << fmt(without.cpu) << " | " << fmt(with.cpu) << " | " << fmt(with.cpu / without.cpu, "%.2f") << " |\n";
    std::fprintf(stderr, "bench loops: featherstone with the loop %.3g, without %.3g cpu s/s: %.2fx\n", with.cpu,
                 without.cpu, with.cpu / without.cpu);
  }

  // Agreement: the three solvers on the hair loop's first second, at fixed steps of each dt (the
  // same steps in every solver), the tip's largest distance between them.
  md << "\n## The three solvers on the hair loop's first second\n\n"
     << "rk4 + projection at fixed steps (max_step_rotation 0: the same steps in every solver). The largest "
     << "distance over the first second between the same link end (every link's lower end, every step) in dense "
     << "and tree, and in dense and featherstone (m). "
     << "Dense and tree share a discretization (maximal coordinates); featherstone's is another (joint space): "
     << "what they share is the limit dt -> 0 (docs/SOLVERS.md, \"What agree means\").\n\n"
     << "| dt | dense - tree (m) | dense - featherstone (m) |\n|---|---|---|\n";
  for (int d : o.agree_dts) {
    const double dt = 1.0 / d;
    std::unique_ptr<Sim> sims[3];
    const char* names[3] = {"dense", "tree", "featherstone"};
    for (int k = 0; k < 3; ++k) sims[k] = loopSim(o.hair_loop, Method{names[k], "rk4", "projection"}, dt, {});
    double tree = 0.0, feather = 0.0;
    const long steps = std::lround(1.0 / dt);
    for (long i = 0; i < steps; ++i) {
      for (auto& s : sims) s->step();
      if (!sims[0]->ok() || !sims[1]->ok() || !sims[2]->ok()) {
        status = 1;
        break;
      }
      for (size_t j = 0; j < sims[0]->chain()->links.size(); ++j) {
        const auto at = [&](int k) { return sims[k]->chain()->bottom(sims[k]->world(), static_cast<int>(j)); };
        tree = std::max(tree, (at(0) - at(1)).norm());
        feather = std::max(feather, (at(0) - at(2)).norm());
      }
    }
    md << "| 1/" << d << " | " << fmt(tree) << " | " << fmt(feather) << " |\n";
    std::fprintf(stderr, "bench loops: agreement at 1/%d: dense-tree %.3g m, dense-featherstone %.3g m\n", d, tree,
                 feather);
    md.flush();
  }
  md << "\nLoad average after: " << loadAverage() << ".\n";
  std::fprintf(stderr, "bench: closed loops -> %s\n", path.c_str());
  return status;
}

}  // namespace ponyhop

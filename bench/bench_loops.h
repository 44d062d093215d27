// `ponyhop bench --loops-only`: closed loops (issue 34; docs/SOLVERS.md, "Closed loops"). The
// four-bar (assets/scenes/four_bar.json, its servo off: a conservative linkage swinging under
// gravity) and the hair loop (assets/scenes/hair_loop.json, on the showcase clip): each solver x
// integrator x stabilization x dt, the loop-closure error (max over the run of every joint's
// error), the energy drift (the four-bar) and the CPU cost per simulated second; featherstone with
// the hair loop's tie against the same tree without it; and the three solvers' agreement on the
// hair loop over its first second; the peer engines on the same four-bar. Its tables go to OUT/loops.md
// (docs/bench/loops.md).
#pragma once

#include <string>
#include <vector>

namespace ponyhop {

struct LoopBenchOptions {
  std::vector<int> dts{60, 240, 1000};          // dt = 1 / d
  double four_bar_seconds = 60.0;               // the four-bar's runs (closure, energy drift)
  double hair_loop_seconds = 10.0;              // the hair loop's runs (closure, cost)
  std::vector<int> agree_dts{240, 1920, 7680};  // the agreement over the hair loop's first second
  int repeats = 2;                              // timed runs of the cost rows, interleaved; the least kept
  std::string four_bar = "assets/scenes/four_bar.json";
  std::string hair_loop = "assets/scenes/hair_loop.json";
  bool peers = true;                   // the peer engines on the four-bar (the modules found in peer_dirs)
  std::vector<std::string> peer_dirs;  // where the modules are (bench_peers.h, peerModuleDirs())
  std::string out = "docs/bench";
  std::string command_line;
};

// Runs the section and writes OUT/loops.md; 0 when the cost and agreement runs finished (a closure
// row that stops is written with its reason: a finding, not a failure).
int runLoopBench(const LoopBenchOptions& options);

}  // namespace ponyhop

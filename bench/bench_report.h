// Writing the bench's results: CSV (every number, failed rows with their reason), Markdown
// (docs/bench/README.md) and gnuplot PNGs (error against cost with the Pareto front; cost
// against N with n and n^3 guides).
#pragma once

#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "bench/bench_run.h"

namespace ponyhop {

// The load average over 1, 5 and 15 min ("0.42 0.61 0.70"), printed beside every timing.
std::string loadAverage();

// One row of bench.csv.
struct BenchRow {
  const BenchCase* bench_case = nullptr;
  std::string method;  // solver/integrator/stabilization, or mujoco/RK4
  std::string solver, integrator, stabilization;
  std::string step = "fixed";  // fixed | auto | tol (bench_run.h, StepControl)
  double dt = 0.0;
  double horizon = 0.0;
  RunResult r;
};

// The reference's convergence check: trajectories at h and h/2 agree within the tolerance up to
// `horizon`; max_diff over [0, check_time].
struct ReferenceCheck {
  std::string case_id;
  std::string method;
  double h = 0.0;
  double max_diff = 0.0;
  double check_time = 0.0;
  double horizon = 0.0;
  std::string status;
};

// A quoted CSV field when it needs one.
std::string csvField(const std::string& s);

void writeBenchCsv(const std::string& path, const std::vector<BenchRow>& rows);
void writeBenchCsv(std::ostream& f, const std::vector<BenchRow>& rows);
// `ponyhop bench --merge`: the rows replace those of the bench.csv at `path` with the same case,
// method and dt (the other rows kept, the new ones at the end); a missing file is created.
// Returns how many rows were replaced. Throws when the file's columns differ.
size_t mergeBenchCsv(const std::string& path, const std::vector<BenchRow>& rows);
void writeReferenceCsv(const std::string& path, const std::vector<ReferenceCheck>& checks);
void writeScalingCsv(const std::string& path, const std::vector<ScalingRow>& rows);

// Indices of the rows of one case (ok runs only) on the Pareto front of (cost per simulated
// second, RMS error): no other run is both cheaper and more accurate. Sorted by cost.
std::vector<size_t> paretoFront(const std::vector<BenchRow>& rows, const std::string& case_id);

// Plots through gnuplot (a subprocess). Returns "" or why no plot was drawn.
std::string plotErrorVsCost(const std::string& dir, const std::vector<BenchRow>& rows, const BenchCase& c);
std::string plotScaling(const std::string& dir, const std::vector<ScalingRow>& rows);
bool haveGnuplot();

std::string fmt(double v, const char* f = "%.3g");

// Cost at equal accuracy (docs/bench/README.md's headline): one completed run as the table reads
// it, from the bench's rows or from a bench.csv.
struct CostPoint {
  std::string case_id, case_title;
  std::string method;  // solver/integrator/stabilization[+auto|+tol], or engine/integrator
  bool peer = false;
  double dt = 0.0;
  bool bounded = false;  // its long run passed the bounds (long_status ok)
  double cost = 0.0;     // us per simulated second
  double err_rms = 0.0;  // m, against the converged reference
  std::string engine() const { return peer ? method.substr(0, method.find('/')) : "ours"; }
};
std::vector<CostPoint> costPoints(const std::vector<BenchRow>& rows);
// The completed runs of a bench.csv (throws when it cannot be read or lacks a column).
std::vector<CostPoint> readCostPoints(const std::string& bench_csv);
// Splits one CSV line (RFC 4180: quoted fields may hold commas and doubled quotes).
std::vector<std::string> splitCsvLine(const std::string& line);

// The accuracy levels of the table: 1e-1 ... 1e-6 m RMS.
inline constexpr double kAccuracyLevels[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6};

// Per case and accuracy level, the cheapest run (cost per simulated second) of ours and of each
// peer engine whose RMS error is at most the level and whose long run stayed bounded; indices
// into the points, -1 when none reaches the level.
struct EqualAccuracyTable {
  std::string case_id, case_title;
  std::vector<std::string> engines;  // the peer engines with runs in this case, by name
  struct Level {
    double level = 0.0;
    int ours = -1;
    std::vector<int> peers;  // per engine
    int cheapest_peer = -1;
  };
  std::vector<Level> levels;
};
std::vector<EqualAccuracyTable> equalAccuracyTables(const std::vector<CostPoint>& points);

// The README's headline section "Cost at equal accuracy": first the lines where a peer is
// cheaper (or none), then a table per case.
void writeEqualAccuracySection(std::ostream& f, const std::vector<CostPoint>& points, const std::string& source);

// "median (smallest-largest)" of v in `format`; "" when v is empty.
std::string spreadOf(const std::vector<double>& v, const char* format);

// Ours against the fastest peer at one N of the scaling sweep: the peer of the smallest median
// cost per step, and per configuration of ours (in row order) the ratio of its cost to that
// peer's in the same round (interleaved neighbours), one per round.
struct ScalingRatio {
  int links = 0;
  std::string peer;
  std::vector<double> peer_us;  // the peer's rounds
  std::vector<std::pair<std::string, std::vector<double>>> ours;
};
std::vector<ScalingRatio> scalingRatios(const std::vector<ScalingRow>& rows);

// The README's section "Scaling": how it was measured, the build flags (`build_notes`, one line
// each), the cost per step with its spread and the joint error per configuration and N, and ours
// against the fastest peer.
void writeScalingSection(std::ostream& f, const std::vector<ScalingRow>& rows,
                         const std::vector<std::string>& build_notes, int rounds, double seconds,
                         const std::string& command, const std::string& load_before, const std::string& load_after);

}  // namespace ponyhop

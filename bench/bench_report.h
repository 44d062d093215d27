// Writing the bench's results: CSV (every number, failed rows with their reason), Markdown
// (docs/bench/README.md) and gnuplot PNGs (error against cost with the Pareto front; cost
// against N with n and n^3 guides).
#pragma once

#include <string>
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

struct ScalingRow {
  std::string solver;
  int links = 0;
  ScalingResult r;
};

// A quoted CSV field when it needs one.
std::string csvField(const std::string& s);

void writeBenchCsv(const std::string& path, const std::vector<BenchRow>& rows);
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

}  // namespace ponyhop

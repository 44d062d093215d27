#include "bench/bench_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>

namespace ponyhop {

std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a.empty() ? "unknown" : a + " " + b + " " + c;
}

namespace {

std::ofstream open(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write the file");
  return f;
}

// Empty for "not applicable" (negative sentinels), else the number.
std::string num(double v) { return v < 0.0 ? "" : fmt(v, "%.6g"); }

std::string gnuplotQuote(std::string s) {
  std::string out;
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    if (ch == '_') out += "\\\\";
    out += ch;
  }
  return out;
}

std::string runGnuplot(const std::string& script_path) {
  if (!haveGnuplot())
    return "gnuplot is not installed (apt-get install gnuplot-nox): no PNG plots, CSV and Markdown only";
  const std::string cmd = "gnuplot '" + script_path + "' 2>'" + script_path + ".log'";
  if (int rc = std::system(cmd.c_str()); rc != 0) return "gnuplot failed (" + script_path + ".log)";
  return "";
}

}  // namespace

std::string fmt(double v, const char* f) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

bool haveGnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"') out += '"';
    out += ch == '\n' ? ' ' : ch;
  }
  return out + "\"";
}

void writeBenchCsv(const std::string& path, const std::vector<BenchRow>& rows) {
  std::ofstream f = open(path);
  f << "case,links,anchor,method,solver,integrator,stabilization,step,dt,status,reason,steps,us_per_step,"
       "us_per_sim_second,horizon,err_rms,err_max,substeps";
  for (auto n : StageTimes::names) f << ",us_" << n;
  f << ",us_other,long_status,long_reason,long_duration,long_reached,energy_drift,energy_drift_rel,joint_drift,"
       "max_speed,tolerance_misses\n";
  for (const BenchRow& row : rows) {
    const BenchCase& c = *row.bench_case;
    const RunResult& r = row.r;
    const bool ran = r.status != "cannot_run";
    const bool ok = r.status == "ok";
    f << c.id << ',' << c.links << ',' << c.anchor << ',' << row.method << ',' << row.solver << ',' << row.integrator
      << ',' << row.stabilization << ',' << row.step << ',' << fmt(row.dt, "%.9g") << ',' << r.status << ','
      << csvField(r.reason) << ',' << (ran ? std::to_string(r.steps) : "") << ',' << (ran ? num(r.us_per_step) : "")
      << ',' << (ran ? num(r.us_per_sim_second) : "") << ',' << fmt(row.horizon, "%.6g") << ','
      << (ok ? num(r.err_rms) : "") << ',' << (ok ? num(r.err_max) : "") << ',' << (ran ? num(r.substeps) : "");
    for (int s = 0; s < StageTimes::kCount; ++s) f << ',' << (ran ? num(r.stage_us[s]) : "");
    f << ',' << (ran ? num(r.other_us) : "") << ',' << (ok ? r.long_status : "skipped") << ','
      << csvField(ok ? r.long_reason : "the horizon run did not complete") << ',' << fmt(c.long_duration, "%.6g") << ','
      << (ok ? num(r.long_reached) : "") << ',' << (ok ? num(r.energy_drift) : "") << ','
      << (ok ? num(r.energy_rel) : "") << ',' << (ok ? num(r.joint_drift) : "") << ',' << (ok ? num(r.max_speed) : "")
      << ',' << (ok ? std::to_string(r.tolerance_misses) : "") << '\n';
  }
}

void writeReferenceCsv(const std::string& path, const std::vector<ReferenceCheck>& checks) {
  std::ofstream f = open(path);
  f << "case,reference,h,h_half,max_tip_difference,over_seconds,horizon_within_1e-7,status\n";
  for (const auto& c : checks) {
    f << c.case_id << ',' << c.method << ',' << fmt(c.h, "%.9g") << ',' << fmt(0.5 * c.h, "%.9g") << ','
      << fmt(c.max_diff, "%.6g") << ',' << fmt(c.check_time, "%.6g") << ',' << fmt(c.horizon, "%.6g") << ','
      << csvField(c.status.empty() ? "ok" : c.status) << '\n';
  }
}

void writeScalingCsv(const std::string& path, const std::vector<ScalingRow>& rows) {
  std::ofstream f = open(path);
  f << "solver,links,status,reason,steps,us_per_step,us_joint_forces\n";
  for (const auto& s : rows) {
    f << s.solver << ',' << s.links << ',' << s.r.status << ',' << csvField(s.r.reason) << ',' << s.r.steps << ','
      << num(s.r.us_per_step) << ',' << num(s.r.joint_forces_us) << '\n';
  }
}

std::vector<size_t> paretoFront(const std::vector<BenchRow>& rows, const std::string& case_id) {
  std::vector<size_t> idx;
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].bench_case->id == case_id && rows[i].r.status == "ok") idx.push_back(i);
  }
  std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) {
    return rows[a].r.us_per_sim_second < rows[b].r.us_per_sim_second ||
           (rows[a].r.us_per_sim_second == rows[b].r.us_per_sim_second && rows[a].r.err_rms < rows[b].r.err_rms);
  });
  std::vector<size_t> front;
  double best = INFINITY;
  for (size_t i : idx) {
    if (rows[i].r.err_rms < best) {
      front.push_back(i);
      best = rows[i].r.err_rms;
    }
  }
  return front;
}

std::string plotErrorVsCost(const std::string& dir, const std::vector<BenchRow>& rows, const BenchCase& c) {
  // One data file: a block per method (points in dt order), then the front.
  const std::string data = dir + "/error_vs_cost_" + c.id + ".dat";
  std::ofstream d = open(data);
  std::map<std::string, std::vector<const BenchRow*>> by_method;
  std::vector<std::string> order;
  for (const auto& row : rows) {
    if (row.bench_case != &c || row.r.status != "ok") continue;
    if (!by_method.count(row.method)) order.push_back(row.method);
    by_method[row.method].push_back(&row);
  }
  if (order.empty()) return "no run of " + c.id + " completed: nothing to plot";
  for (const auto& m : order) {
    d << "# " << m << '\n';
    for (const BenchRow* r : by_method[m]) {
      d << r->r.us_per_sim_second * 1e-6 << ' ' << std::max(r->r.err_rms, 1e-16) << ' ' << r->dt << '\n';
    }
    d << "\n\n";
  }
  d << "# pareto\n";
  for (size_t i : paretoFront(rows, c.id)) {
    d << rows[i].r.us_per_sim_second * 1e-6 << ' ' << std::max(rows[i].r.err_rms, 1e-16) << ' ' << rows[i].dt << '\n';
  }
  d.close();
  const std::string script = dir + "/error_vs_cost_" + c.id + ".gp";
  std::ofstream g = open(script);
  g << "set terminal pngcairo size 1400,900 font ',10'\n"
    << "set output '" << dir << "/error_vs_cost_" << c.id << ".png'\n"
    << "set title \"" << gnuplotQuote(c.title)
    << ": RMS error over the converged horizon against cost (one point per dt)\"\n"
    << "set logscale xy\nset format x '10^{%L}'\nset format y '10^{%L}'\n"
    << "set xlabel 'cost: wall seconds per simulated second'\nset ylabel 'RMS error of the tracked point (m)'\n"
    << "set key outside right top font ',9' spacing 1.2\nset grid\n"
    << "plot ";
  // Few distinguishable series: the colour says the integrator, the marker the solver, the dash
  // the stabilization; the legend lists those families once each instead of every combination.
  const auto integratorColour = [](const std::string& i) -> const char* {
    if (i == "symplectic_euler" || i == "Euler") return "#1f77b4";
    if (i == "rk4" || i == "RK4") return "#d62728";
    if (i == "rattle") return "#2ca02c";
    if (i == "implicit_euler") return "#9467bd";
    return "#7f7f7f";
  };
  const auto solverPoint = [](const std::string& s) {
    if (s == "dense") return 7;
    if (s == "tree") return 5;
    if (s == "featherstone") return 9;
    if (s == "bullet") return 11;
    if (s == "ode") return 3;
    if (s == "dart") return 15;
    return 13;  // mujoco
  };
  const auto stabDash = [](const std::string& st) { return st == "baumgarte" ? 2 : st == "projection" ? 4 : 1; };
  std::vector<std::string> integrators, solvers, stabs;
  const auto note = [](std::vector<std::string>& v, const std::string& x) {
    if (!x.empty() && std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
  };
  for (size_t i = 0; i < order.size(); ++i) {
    const BenchRow& r = *by_method[order[i]].front();
    note(integrators, r.integrator);
    note(solvers, r.solver);
    if (r.stabilization != "-") note(stabs, r.stabilization);
    const bool auto_step = r.step != "fixed";
    const bool peer = std::count(order[i].begin(), order[i].end(), '/') == 1;  // a peer engine: engine/integrator
    g << "'" << data << "' index " << i << " using 1:2 with linespoints lw " << (auto_step || peer ? 2.5 : 1.2)
      << " dt " << stabDash(r.stabilization) << " pt " << solverPoint(r.solver) << " ps " << (auto_step ? 1.6 : 1.0)
      << " lc rgb '" << integratorColour(r.integrator) << "' notitle, ";
  }
  for (const auto& i : integrators)
    g << "NaN with lines lw 4 lc rgb '" << integratorColour(i) << "' title \"integrator " << gnuplotQuote(i) << "\", ";
  for (const auto& s2 : solvers)
    g << "NaN with points pt " << solverPoint(s2) << " ps 1.5 lc rgb 'black' title \"solver " << gnuplotQuote(s2)
      << "\", ";
  for (const auto& st : stabs)
    g << "NaN with lines lw 1.5 dt " << stabDash(st) << " lc rgb 'black' title \"stabilization " << gnuplotQuote(st)
      << "\", ";
  g << "NaN with linespoints lw 2.5 pt 6 ps 1.6 lc rgb 'gray30' title \"thick, large: step control (+auto, +tol)\", ";
  g << "'" << data << "' index " << order.size()
    << " using 1:2 with steps lw 3 lc rgb 'black' dt 2 title 'Pareto front', '" << data << "' index " << order.size()
    << " using 1:2 with points pt 6 ps 2.2 lw 2 lc rgb 'black' notitle\n";
  g.close();
  return runGnuplot(script);
}

std::string plotScaling(const std::string& dir, const std::vector<ScalingRow>& rows) {
  const std::string data = dir + "/scaling.dat";
  std::ofstream d = open(data);
  std::vector<std::string> solvers;
  for (const auto& r : rows) {
    if (std::find(solvers.begin(), solvers.end(), r.solver) == solvers.end()) solvers.push_back(r.solver);
  }
  double y8 = 0.0;  // guide lines through the cheapest solver's cost at the smallest N
  int n0 = 0;
  for (const auto& s : solvers) {
    d << "# " << s << '\n';
    for (const auto& r : rows) {
      if (r.solver != s || r.r.status != "ok") continue;
      d << r.links << ' ' << r.r.us_per_step << '\n';
      if (n0 == 0 || r.links < n0 || (r.links == n0 && r.r.us_per_step < y8)) {
        n0 = r.links;
        y8 = r.r.us_per_step;
      }
    }
    d << "\n\n";
  }
  d.close();
  if (n0 == 0) return "no scaling run completed: nothing to plot";
  const std::string script = dir + "/scaling.gp";
  std::ofstream g = open(script);
  g << "set terminal pngcairo size 1000,700 font ',10'\n"
    << "set output '" << dir << "/scaling.png'\n"
    << "set title 'Cost per step against chain length (hanging chain, dt = 1/1920 s; ours: symplectic Euler, no "
       "stabilization; peers: their own step)'\n"
    << "set logscale xy\nset xlabel 'links N'\nset ylabel 'microseconds per step'\nset key left top\nset grid\n"
    << "plot ";
  // A colour per series (ten, none repeated: gnuplot's own cycle has eight); ours solid and
  // thick, the peers (engine/method) thin, dashed, each with its own marker.
  static const char* kColors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                  "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"};
  for (size_t i = 0; i < solvers.size(); ++i) {
    const bool peer = solvers[i].find('/') != std::string::npos;
    g << "'" << data << "' index " << i << " using 1:2 with linespoints lc rgb '" << kColors[i % 10] << "' "
      << (peer ? "lw 1.5 dt 2 pt " + std::to_string(4 + i % 8) : std::string("lw 3 pt 7")) << " title '" << solvers[i]
      << "', ";
  }
  g << fmt(y8, "%.6g") << "*(x/" << n0 << ".0) with lines dt 2 lc rgb 'gray40' title 'guide: n', " << fmt(y8, "%.6g")
    << "*(x/" << n0 << ".0)**3 with lines dt 3 lc rgb 'gray20' title 'guide: n^3'\n";
  g.close();
  return runGnuplot(script);
}

}  // namespace ponyhop

#include "bench/bench_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
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
  writeBenchCsv(f, rows);
}

void writeBenchCsv(std::ostream& f, const std::vector<BenchRow>& rows) {
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

size_t mergeBenchCsv(const std::string& path, const std::vector<BenchRow>& rows) {
  std::ostringstream fresh;
  writeBenchCsv(fresh, rows);
  std::istringstream in_fresh(fresh.str());
  std::string header, line;
  std::getline(in_fresh, header);
  // A row is (case, method, dt): columns 0, 3 and 8, dt as written (%.9g) on both sides.
  const auto key = [](const std::string& l) {
    const std::vector<std::string> v = splitCsvLine(l);
    return v.size() > 8 ? v[0] + ',' + v[3] + ',' + v[8] : l;
  };
  std::vector<std::string> added;
  std::set<std::string> keys;
  while (std::getline(in_fresh, line)) {
    added.push_back(line);
    keys.insert(key(line));
  }
  std::vector<std::string> kept;
  size_t replaced = 0;
  {
    std::ifstream old(path);
    std::string old_header;
    if (old && std::getline(old, old_header) && old_header != header) {
      throw std::runtime_error(path + ": its columns differ from this bench's; run the whole bench instead of --merge");
    }
    while (std::getline(old, line)) {
      if (keys.count(key(line)))
        ++replaced;
      else
        kept.push_back(line);
    }
  }
  std::ofstream f = open(path);
  f << header << '\n';
  for (const auto& l : kept) f << l << '\n';
  for (const auto& l : added) f << l << '\n';
  return replaced;
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
  f << "config,drift,links,status,reason,steps,rounds,us_per_step,us_min,us_max,joint_error\n";
  for (const auto& s : rows) {
    const bool ok = s.status == "ok" && !s.us_per_step.empty();
    const auto [lo, hi] = std::minmax_element(s.us_per_step.begin(), s.us_per_step.end());
    f << s.config << ',' << csvField(s.drift) << ',' << s.links << ',' << s.status << ',' << csvField(s.reason) << ','
      << s.steps << ',' << s.us_per_step.size() << ',' << (ok ? num(s.us()) : "") << ',' << (ok ? num(*lo) : "") << ','
      << (ok ? num(*hi) : "") << ',' << (s.status == "ok" || s.status == "failed" ? num(s.joint_error) : "") << '\n';
  }
}

std::string spreadOf(const std::vector<double>& v, const char* format) {
  if (v.empty()) return "";
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return fmt(median(v), format) + " (" + fmt(*lo, format) + "-" + fmt(*hi, format) + ")";
}

std::vector<ScalingRatio> scalingRatios(const std::vector<ScalingRow>& rows) {
  std::vector<int> sizes;
  for (const auto& r : rows) {
    if (std::find(sizes.begin(), sizes.end(), r.links) == sizes.end()) sizes.push_back(r.links);
  }
  std::vector<ScalingRatio> out;
  for (int n : sizes) {
    const ScalingRow* fastest = nullptr;
    for (const auto& r : rows) {
      if (r.links == n && r.peer && r.status == "ok" && !r.us_per_step.empty() && (!fastest || r.us() < fastest->us()))
        fastest = &r;
    }
    if (!fastest) continue;
    ScalingRatio q;
    q.links = n;
    q.peer = fastest->config;
    q.peer_us = fastest->us_per_step;
    for (const auto& r : rows) {
      if (r.links != n || r.peer) continue;
      std::vector<double> ratio;
      if (r.status == "ok") {
        for (size_t k = 0; k < std::min(r.us_per_step.size(), q.peer_us.size()); ++k)
          ratio.push_back(r.us_per_step[k] / q.peer_us[k]);
      }
      q.ours.emplace_back(r.config, std::move(ratio));
    }
    out.push_back(std::move(q));
  }
  return out;
}

void writeScalingSection(std::ostream& f, const std::vector<ScalingRow>& rows,
                         const std::vector<std::string>& build_notes, int rounds, double seconds,
                         const std::string& command, const std::string& load_before, const std::string& load_after) {
  f << "\n## Scaling\n\n![cost against N](scaling.png)\n\n"
    << "Made by `" << command << "`; load average before " << load_before << ", after " << load_after
    << ". The chain released horizontally from a fixed anchor (the bench's fixed-anchor case), in motion: every "
       "configuration, ours and the peers', is timed over the same first "
    << fmt(seconds, "%g") << " s of its swing at dt = 1/1920 s (fixed steps: one step of dt per step, no automatic "
    << "substeps), from t = 0 each round. " << rounds
    << " interleaved rounds (every configuration in turn, every other round in reverse order), the cost of a step "
       "the thread's CPU time; each cell gives the median round and, in brackets, the smallest and largest. Ours: "
       "`Sim::step`, the step `ponyhop sim` takes, with the per-stage clock off as the peers' steps carry none; "
       "every solver with the drift control it ships with (tree and dense: position projection after a "
       "symplectic Euler step, and RATTLE, the default integrator; featherstone: joint coordinates, no drift) and "
       "symplectic Euler without stabilization, labelled *no drift control*. Joint error: the largest joint gap "
       "over the timed run (sampled every 1/240 s; the peers' from their links' ends). Skipped: its first step put the "
       "round over the CPU budget. Left out is what `ponyhop sim` writes (`--csv`: a summary row's energy "
       "and joint error once per 1 ms).\n\n";
  if (!build_notes.empty()) {
    f << "Build flags:\n\n";
    for (const auto& n : build_notes) f << "- " << n << '\n';
    f << '\n';
  }
  std::vector<int> sizes;
  std::vector<std::pair<std::string, std::string>> configs;  // name, drift
  for (const auto& r : rows) {
    if (std::find(sizes.begin(), sizes.end(), r.links) == sizes.end()) sizes.push_back(r.links);
    if (std::find_if(configs.begin(), configs.end(), [&](const auto& c) { return c.first == r.config; }) ==
        configs.end())
      configs.emplace_back(r.config, r.drift);
  }
  const auto find = [&](const std::string& config, int n) -> const ScalingRow* {
    for (const auto& r : rows) {
      if (r.config == config && r.links == n) return &r;
    }
    return nullptr;
  };
  f << "### Cost per step (CPU us) and joint error\n\n| configuration | drift control | N | us/step | joint error "
       "(m) | status |\n|---|---|---|---|---|---|\n";
  for (const auto& [config, drift] : configs) {
    for (int n : sizes) {
      const ScalingRow* r = find(config, n);
      if (!r) continue;
      std::string why = r->reason;
      std::replace(why.begin(), why.end(), '\n', ' ');
      if (why.size() > 120) why = why.substr(0, 117) + "...";
      const bool ran = r->status == "ok" || r->status == "failed";
      f << "| " << config << " | " << drift << " | " << n << " | " << spreadOf(r->us_per_step, "%.3g") << " | "
        << (ran ? fmt(r->joint_error, "%.2g") : "") << " | " << r->status << (why.empty() ? "" : ": " + why) << " |\n";
    }
  }
  const auto ratios = scalingRatios(rows);
  if (ratios.empty()) return;
  f << "\n### Ours / fastest peer\n\nPer round, our cost per step divided by the fastest peer's (the smallest "
       "median at that N) in the same round; the median round and, in brackets, the smallest and largest (below 1: "
       "ours is cheaper).\n\n| N | fastest peer | its us/step |";
  for (const auto& o : ratios.front().ours) {
    const ScalingRow* r = find(o.first, ratios.front().links);
    f << ' ' << o.first << (r && r->drift.rfind("none", 0) == 0 ? " (no drift control)" : "") << " |";
  }
  f << "\n|---|---|---|";
  for (size_t i = 0; i < ratios.front().ours.size(); ++i) f << "---|";
  f << '\n';
  for (const auto& q : ratios) {
    f << "| " << q.links << " | " << q.peer << " | " << spreadOf(q.peer_us, "%.3g") << " |";
    for (const auto& o : q.ours) f << ' ' << (o.second.empty() ? "-" : spreadOf(o.second, "%.2f")) << " |";
    f << '\n';
  }
}

std::vector<std::string> splitCsvLine(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      out.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

std::vector<CostPoint> costPoints(const std::vector<BenchRow>& rows) {
  std::vector<CostPoint> out;
  for (const BenchRow& r : rows) {
    if (r.r.status != "ok") continue;
    out.push_back({r.bench_case->id, r.bench_case->title, r.method, r.stabilization == "-", r.dt,
                   r.r.long_status == "ok", r.r.us_per_sim_second, r.r.err_rms});
  }
  return out;
}

std::vector<CostPoint> readCostPoints(const std::string& bench_csv) {
  std::ifstream f(bench_csv);
  if (!f) throw std::runtime_error(bench_csv + ": cannot read the file");
  std::string line;
  std::getline(f, line);
  const std::vector<std::string> header = splitCsvLine(line);
  const auto column = [&](const char* name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw std::runtime_error(bench_csv + ": no column '" + name + "'");
    return static_cast<size_t>(it - header.begin());
  };
  const size_t c_case = column("case"), c_links = column("links"), c_anchor = column("anchor"),
               c_method = column("method"), c_stab = column("stabilization"), c_dt = column("dt"),
               c_status = column("status"), c_long = column("long_status"), c_cost = column("us_per_sim_second"),
               c_err = column("err_rms");
  std::vector<CostPoint> out;
  while (std::getline(f, line)) {
    const std::vector<std::string> v = splitCsvLine(line);
    if (v.size() != header.size() || v[c_status] != "ok") continue;
    const int links = std::atoi(v[c_links].c_str());
    out.push_back({v[c_case], links > 0 ? "chain N=" + v[c_links] + " " + v[c_anchor] : v[c_case], v[c_method],
                   v[c_stab] == "-", std::strtod(v[c_dt].c_str(), nullptr), v[c_long] == "ok",
                   std::strtod(v[c_cost].c_str(), nullptr), std::strtod(v[c_err].c_str(), nullptr)});
  }
  return out;
}

std::vector<EqualAccuracyTable> equalAccuracyTables(const std::vector<CostPoint>& points) {
  std::vector<EqualAccuracyTable> tables;
  const auto table = [&](const CostPoint& p) -> EqualAccuracyTable& {
    for (auto& t : tables) {
      if (t.case_id == p.case_id) return t;
    }
    tables.push_back({p.case_id, p.case_title, {}, {}});
    return tables.back();
  };
  for (const CostPoint& p : points) {
    EqualAccuracyTable& t = table(p);
    if (p.peer && std::find(t.engines.begin(), t.engines.end(), p.engine()) == t.engines.end())
      t.engines.push_back(p.engine());
  }
  for (EqualAccuracyTable& t : tables) {
    // By name: the columns do not move when a --merge run puts an engine's rows at the end.
    std::sort(t.engines.begin(), t.engines.end());
    for (double level : kAccuracyLevels) {
      EqualAccuracyTable::Level row;
      row.level = level;
      row.peers.assign(t.engines.size(), -1);
      const auto cheaper = [&](int candidate, int best) {
        return best < 0 || points[candidate].cost < points[best].cost;
      };
      for (size_t i = 0; i < points.size(); ++i) {
        const CostPoint& p = points[i];
        if (p.case_id != t.case_id || !p.bounded || !(p.err_rms <= level)) continue;
        const int k = static_cast<int>(i);
        if (!p.peer) {
          if (cheaper(k, row.ours)) row.ours = k;
          continue;
        }
        const size_t e = std::find(t.engines.begin(), t.engines.end(), p.engine()) - t.engines.begin();
        if (cheaper(k, row.peers[e])) row.peers[e] = k;
        if (cheaper(k, row.cheapest_peer)) row.cheapest_peer = k;
      }
      t.levels.push_back(std::move(row));
    }
  }
  return tables;
}

void writeEqualAccuracySection(std::ostream& f, const std::vector<CostPoint>& points, const std::string& source) {
  const auto tables = equalAccuracyTables(points);
  const auto cost = [&](int i) { return points[i].cost; };
  const auto cell = [&](int i) {
    if (i < 0) return std::string("-");
    const CostPoint& p = points[i];
    return "`" + p.method + "` 1/" + fmt(1.0 / p.dt, "%.0f") + ": " + fmt(p.cost * 1e-3) + " (" +
           fmt(p.err_rms, "%.2g") + " m)";
  };
  f << "\n## Cost at equal accuracy\n\n";
  // The first lines: where a peer is cheaper, and where the goal (ours at most 0.5x the cheapest
  // peer) is missed.
  std::vector<std::string> cheaper_peer, missed, met;
  for (const auto& t : tables) {
    for (const auto& l : t.levels) {
      if (l.ours < 0 && l.cheapest_peer >= 0) {
        cheaper_peer.push_back(t.case_title + " at " + fmt(l.level, "%g") + " m: only a peer reaches it (" +
                               cell(l.cheapest_peer) + ")");
        continue;
      }
      if (l.ours < 0 || l.cheapest_peer < 0) continue;
      const double r = cost(l.ours) / cost(l.cheapest_peer);
      const std::string what = t.case_title + " at " + fmt(l.level, "%g") + " m: ours / " +
                               points[l.cheapest_peer].method + " = " + fmt(r, "%.2f");
      (r > 1.0 ? cheaper_peer : r > 0.5 ? missed : met).push_back(what);
    }
  }
  f << "**Where a peer is cheaper** (at equal accuracy, per simulated second): "
    << (cheaper_peer.empty() ? std::string("nowhere.") : std::to_string(cheaper_peer.size()) + " of the levels:")
    << "\n\n";
  for (const auto& s : cheaper_peer) f << "- " << s << '\n';
  if (!cheaper_peer.empty()) f << '\n';
  f << "**Ours dearer than 0.5x the cheapest peer** (the goal): "
    << (missed.empty() ? std::string("nowhere.") : std::to_string(missed.size()) + " of the levels:") << "\n\n";
  for (const auto& s : missed) f << "- " << s << '\n';
  if (!missed.empty()) f << '\n';
  f << "Met (ours at most 0.5x the cheapest peer): " << met.size() << " of the levels a peer reaches.\n\n"
    << "Per case and accuracy level (RMS distance of the chain's tip from the converged reference over the "
       "horizon, the error columns below): the cheapest run of ours and of each peer engine that reaches it, over "
       "every method and dt the bench ran, among the runs whose long run stayed bounded (a run that reaches the "
       "level and then blows up is no choice); cost in ms of wall time per simulated second (the timed repeats' "
       "median), its error in brackets. Ours / peer: ours against the cheapest peer (below 1: ours is cheaper). The "
       "peers run every chain case; on the shaking anchor each is given the anchor's prescribed motion as its API "
       "allows (bench/peer.h: MuJoCo slide joints forced to the path's acceleration, Bullet a floating base of "
       "1e12 kg forced likewise, ODE a kinematic body, DART a velocity-actuated translational joint). From "
    << source << ".\n\n";
  for (const auto& t : tables) {
    f << "### " << t.case_title << "\n\n| RMS error at most (m) | ours |";
    for (const auto& e : t.engines) f << ' ' << e << " |";
    f << (t.engines.empty() ? "" : " ours / cheapest peer |") << "\n|---|---|";
    for (size_t i = 0; i < t.engines.size(); ++i) f << "---|";
    f << (t.engines.empty() ? "" : "---|") << '\n';
    for (const auto& l : t.levels) {
      f << "| " << fmt(l.level, "%g") << " | " << cell(l.ours) << " |";
      for (int p : l.peers) f << ' ' << cell(p) << " |";
      if (!t.engines.empty()) {
        f << ' '
          << (l.ours >= 0 && l.cheapest_peer >= 0 ? fmt(cost(l.ours) / cost(l.cheapest_peer), "%.2f")
              : l.cheapest_peer >= 0              ? std::string("only peers")
              : l.ours >= 0                       ? std::string("no peer")
                                                  : std::string("-"))
          << " |";
      }
      f << '\n';
    }
    f << '\n';
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
  std::vector<const ScalingRow*> series;  // the first row of each configuration
  for (const auto& r : rows) {
    if (std::none_of(series.begin(), series.end(), [&](const ScalingRow* s) { return s->config == r.config; }))
      series.push_back(&r);
  }
  double y0 = 0.0;  // guide lines through the cheapest configuration's cost at the smallest N
  int n0 = 0;
  // The axes span the measured points (the n^3 guide would otherwise stretch them to 1e8 us).
  double y_lo = std::numeric_limits<double>::infinity(), y_hi = 0.0;
  int n_hi = 0;
  for (const ScalingRow* s : series) {
    d << "# " << s->config << '\n';
    for (const auto& r : rows) {
      if (r.config != s->config || r.status != "ok" || r.us_per_step.empty()) continue;
      const auto [lo, hi] = std::minmax_element(r.us_per_step.begin(), r.us_per_step.end());
      d << r.links << ' ' << r.us() << ' ' << *lo << ' ' << *hi << '\n';
      y_lo = std::min(y_lo, *lo);
      y_hi = std::max(y_hi, *hi);
      n_hi = std::max(n_hi, r.links);
      if (n0 == 0 || r.links < n0 || (r.links == n0 && r.us() < y0)) {
        n0 = r.links;
        y0 = r.us();
      }
    }
    d << "\n\n";
  }
  d.close();
  if (n0 == 0) return "no scaling run completed: nothing to plot";
  const std::string script = dir + "/scaling.gp";
  std::ofstream g = open(script);
  g << "set terminal pngcairo size 1100,750 font ',10'\n"
    << "set output '" << dir << "/scaling.png'\n"
    << "set title \"Cost per step against chain length, in motion\\n(chain released horizontally, dt = 1/1920 s; "
       "median and range of interleaved rounds, thread CPU)\"\n"
    << "set logscale xy\nset xlabel 'links N'\nset ylabel 'CPU microseconds per step'\n"
    << "set xrange [" << fmt(n0 / 1.5, "%.6g") << ":" << fmt(n_hi * 1.5, "%.6g") << "]\nset yrange ["
    << fmt(y_lo / 2.0, "%.6g") << ":" << fmt(y_hi * 2.0, "%.6g") << "]\n"
    << "set key below font ',9' maxcols 3 width -8\nset grid\nplot ";
  // A colour per series (gnuplot's own cycle has eight); ours solid and thick, the peers
  // (engine/method) thin, dashed, each with its own marker; error bars: the rounds' range.
  static const char* kColors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
                                  "#17becf", "#bcbd22", "#7f7f7f", "#393b79", "#637939", "#ad494a"};
  constexpr size_t kColorCount = sizeof(kColors) / sizeof(kColors[0]);
  for (size_t i = 0; i < series.size(); ++i) {
    const ScalingRow& s = *series[i];
    const std::string style = s.peer ? "lw 1.5 dt 2 pt " + std::to_string(4 + i % 8)
                                     : std::string(s.drift.rfind("none", 0) == 0 ? "lw 2 dt 3 pt 7" : "lw 3 pt 7");
    // The drift control in brackets where the configuration's name does not already end with it.
    const bool named = s.config.size() >= s.drift.size() &&
                       s.config.compare(s.config.size() - s.drift.size(), s.drift.size(), s.drift) == 0;
    const std::string title = gnuplotQuote(s.peer || named ? s.config : s.config + " (" + s.drift + ")");
    g << "'" << data << "' index " << i << " using 1:2:3:4 with yerrorlines lc rgb '" << kColors[i % kColorCount]
      << "' " << style << " title \"" << title << "\", ";
  }
  g << fmt(y0, "%.6g") << "*(x/" << n0 << ".0) with lines dt 2 lc rgb 'gray40' title 'guide: n', " << fmt(y0, "%.6g")
    << "*(x/" << n0 << ".0)**3 with lines dt 3 lc rgb 'gray20' title 'guide: n^3'\n";
  g.close();
  return runGnuplot(script);
}

}  // namespace ponyhop

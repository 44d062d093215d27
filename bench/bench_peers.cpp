#include "bench/bench_peers.h"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "physics/stage_times.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;

// The engines that may have a module, in the order of their notes.
struct Engine {
  const char* name;     // in the notes: "MuJoCo"
  const char* module;   // ponyhop-peer-<module>.so
  const char* package;  // the Debian package that has CMake build the module
};
constexpr Engine kEngines[] = {{"MuJoCo", "mujoco", "libmujoco-dev"},
                               {"Bullet", "bullet", "libbullet-dev"},
                               {"ODE", "ode", "libode-dev"},
                               {"DART", "dart", "libdart-dev"}};

}  // namespace

PeerChain peerChainOf(const Sim& sim) {
  PeerChain m;
  const Chain& ch = *sim.chain();
  m.anchor = ch.anchor(sim.world());
  m.length = ch.length;
  m.gravity = sim.world().params().gravity;
  for (size_t i = 0; i < ch.links.size(); ++i) {
    const RigidBody& b = sim.world().body(ch.links[i]);
    m.mass.push_back(b.mass);
    m.inertia.push_back(b.inertia);
    m.q.push_back(b.q);
    m.radius.push_back(ch.radii[i]);
  }
  return m;
}

RunResult benchPeerRun(const Peer& peer, const PeerChain& chain, double dt, double horizon, int repeats,
                       double long_duration, const Trajectory& reference, double e_start) {
  RunResult r;
  const long n = std::lround(horizon / dt);
  const long every = std::max(1L, std::lround(kBenchGrid / dt));
  r.steps = n;
  Trajectory traj;
  traj.stride = every * dt;
  std::vector<double> per_step;
  std::unique_ptr<PeerSim> first;
  double e0 = 0.0;
  for (int rep = 0; rep < std::max(1, repeats); ++rep) {
    std::string error;
    auto s = peer.make(chain, dt, error);
    if (!s) {
      r.status = "failed";
      r.reason = error;
      return r;
    }
    if (rep == 0) {
      traj.p.push_back(s->tip());
      e0 = s->energy();
    }
    Clock::duration total{};
    long taken = 0;
    bool ok = true;
    for (long i = 1; i <= n; ++i) {
      const auto t0 = Clock::now();
      s->step();
      total += Clock::now() - t0;
      ++taken;
      if (!(ok = s->finite())) break;
      if (rep == 0 && i % every == 0) traj.p.push_back(s->tip());
    }
    per_step.push_back(durationSeconds(total) / std::max(1L, taken));
    if (!ok) {
      char b[160];
      std::snprintf(b, sizeof b, "t = %.6g s: %s's state became non-finite or ran away (dt %.6g s)", s->time(),
                    peer.name.c_str(), dt);
      r.status = "failed";
      r.reason = b;
      r.steps = taken;
      break;
    }
    if (rep == 0) first = std::move(s);
  }
  r.us_per_step = 1e6 * median(per_step);
  r.us_per_sim_second = r.us_per_step / dt;
  if (r.status != "ok") return r;
  const auto err = trajectoryError(traj, reference, horizon);
  r.err_rms = err[0];
  r.err_max = err[1];
  // Long run: energy drift against the peer's own energy at t = 0.
  PeerSim& s = *first;
  const long total = std::lround(long_duration / dt);
  const long sample = std::max(1L, std::lround((1.0 / 240.0) / dt));
  double drift = 0.0;
  Eigen::Vector3d prev = s.tip();
  bool ok = true;
  for (long i = n + 1; i <= total; ++i) {
    s.step();
    if (i % sample != 0) continue;
    if (!(ok = s.finite())) break;
    drift = std::max(drift, std::abs(s.energy() - e0));
    const Eigen::Vector3d p = s.tip();
    r.max_speed = std::max(r.max_speed, (p - prev).norm() / (sample * dt));
    prev = p;
  }
  r.long_reached = s.time();
  r.energy_drift = drift;
  r.energy_rel = std::abs(e_start) > 0.0 ? drift / std::abs(e_start) : drift;
  if (!ok) {
    r.long_status = "stopped";
    r.long_reason = peer.name + "'s state became non-finite or ran away";
  } else if (r.energy_rel > 1.0) {
    r.long_status = "unbounded";
    r.long_reason = "energy drift beyond E0";
  }
  return r;
}

ScalingResult benchPeerScaling(const Peer& peer, const PeerChain& chain, double dt, double budget) {
  ScalingResult s;
  std::string error;
  auto sim = peer.make(chain, dt, error);
  if (!sim) {
    s.status = "failed";
    s.reason = error;
    return s;
  }
  s.us_per_step = 1e6 * timeSteps(
                            [&] {
                              sim->step();
                              return true;
                            },
                            budget, s.steps);
  if (!sim->finite()) {
    s.status = "failed";
    s.reason = peer.name + "'s state became non-finite";
  }
  return s;
}

PeerModules loadPeerModules(const std::vector<std::string>& dirs) {
  PeerModules m;
  for (const Engine& e : kEngines) {
    const std::string file = std::string("ponyhop-peer-") + e.module + ".so";
    const std::string no_rows = std::string(": no ") + e.name + " rows.";
    std::string path;
    for (const std::string& d : dirs) {
      std::error_code ec;
      if (!d.empty() && fs::is_regular_file(fs::path(d) / file, ec)) {
        path = (fs::path(d) / file).string();
        break;
      }
    }
    if (path.empty()) {
      m.notes.push_back(std::string(e.name) + "'s module " + file +
                        " was not found (it is built when configure finds " + e.package + ")" + no_rows);
      continue;
    }
    // Never closed: the peers' functions and the engine's own state live in the module.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      m.notes.push_back(std::string(e.name) + "'s module " + path + " failed to load (" + dlerror() + ")" + no_rows);
      continue;
    }
    const auto entry = reinterpret_cast<decltype(&ponyhop_peers_v1)>(dlsym(handle, kPeerEntry));
    if (!entry) {
      m.notes.push_back(std::string(e.name) + "'s module " + path + " has no " + kPeerEntry +
                        " (built by another version of ponyhop?)" + no_rows);
      continue;
    }
    std::vector<Peer> peers;
    entry(&peers);
    if (peers.empty()) {
      m.notes.push_back(std::string(e.name) + "'s module " + path + " has no peers" + no_rows);
      continue;
    }
    std::string names;
    for (const Peer& p : peers) names += (names.empty() ? "" : ", ") + p.name;
    m.notes.push_back(peers.front().version + " (" + names + ")");
    m.peers.insert(m.peers.end(), peers.begin(), peers.end());
  }
  return m;
}

std::vector<std::string> peerModuleDirs() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path bin = exe.parent_path();
  // PREFIX/BINDIR/ponyhop -> PREFIX/LIBDIR/ponyhop: climb one folder per component of BINDIR.
  fs::path prefix = bin;
  for ([[maybe_unused]] const auto& part : fs::path(PONYHOP_INSTALL_BINDIR)) prefix = prefix.parent_path();
  return {bin.string(), (prefix / PONYHOP_INSTALL_PEERDIR).string()};
}

}  // namespace ponyhop

#include "app/bench_peers.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace ponyhop {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

double PeerSim::energy() {
  links(scratch_);
  double e = 0.0;
  for (size_t i = 0; i < scratch_.size(); ++i) {
    const PeerLink& l = scratch_[i];
    const Eigen::Matrix3d r = l.q.normalized().toRotationMatrix();
    const Eigen::Vector3d w_body = r.transpose() * l.w;
    e += 0.5 * chain_.mass[i] * l.v.squaredNorm() + 0.5 * w_body.dot(chain_.inertia[i].cwiseProduct(w_body)) -
         chain_.mass[i] * chain_.gravity.dot(l.x);
  }
  return e;
}

Eigen::Vector3d PeerSim::tip() {
  links(scratch_);
  const PeerLink& l = scratch_.back();
  return l.x + l.q.normalized() * Eigen::Vector3d(0.0, 0.0, -0.5 * chain_.length);
}

bool PeerSim::finite() {
  links(scratch_);
  for (const PeerLink& l : scratch_) {
    for (const Eigen::Vector3d& v : {l.x, l.v, l.w}) {
      if (!v.allFinite() || v.cwiseAbs().maxCoeff() > 1e10) return false;
    }
    if (!l.q.coeffs().allFinite()) return false;
  }
  return true;
}

PeerChain peerChainOf(const Sim& rt) {
  PeerChain m;
  const Chain& ch = *rt.chain();
  m.anchor = ch.anchor(rt.world());
  m.length = ch.length;
  m.gravity = rt.world().params().gravity;
  for (size_t i = 0; i < ch.links.size(); ++i) {
    const RigidBody& b = rt.world().body(ch.links[i]);
    m.mass.push_back(b.mass);
    m.inertia.push_back(b.inertia);
    m.q.push_back(b.q);
    m.radius.push_back(ch.radii[i]);
  }
  return m;
}

std::vector<Peer> availablePeers() {
  std::vector<Peer> all;
  for (auto&& list : {mujocoPeers(), bulletPeers(), odePeers(), dartPeers()}) all.insert(all.end(), list.begin(), list.end());
  return all;
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
    per_step.push_back(seconds(total) / std::max(1L, taken));
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

// Engines not compiled in contribute nothing.
#ifndef PONYHOP_HAVE_MUJOCO
std::vector<Peer> mujocoPeers() { return {}; }
#endif
#ifndef PONYHOP_HAVE_BULLET
std::vector<Peer> bulletPeers() { return {}; }
#endif
#ifndef PONYHOP_HAVE_ODE
std::vector<Peer> odePeers() { return {}; }
#endif
#ifndef PONYHOP_HAVE_DART
std::vector<Peer> dartPeers() { return {}; }
#endif

std::vector<std::string> peerNotes() {
  std::vector<std::string> notes;
  const auto note = [&](const std::vector<Peer>& peers, const char* engine, const char* package) {
    if (peers.empty()) {
      notes.push_back(std::string(engine) + " was not found at configure time (optional: " + package + "): no " +
                      engine + " rows.");
      return;
    }
    std::string names;
    for (const Peer& p : peers) names += (names.empty() ? "" : ", ") + p.name;
    notes.push_back(peers.front().version + " (" + names + ")");
  };
  note(mujocoPeers(), "MuJoCo", "libmujoco-dev");
  note(bulletPeers(), "Bullet", "libbullet-dev");
  note(odePeers(), "ODE", "libode-dev");
  note(dartPeers(), "DART", "libdart-dev");
  return notes;
}

}  // namespace ponyhop

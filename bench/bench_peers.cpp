#include "bench/bench_peers.h"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

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

// The first line a shell command prints ("" when it fails).
std::string firstLine(const std::string& cmd) {
  std::string out;
  if (FILE* p = popen((cmd + " 2>/dev/null").c_str(), "r")) {
    char b[512];
    if (std::fgets(b, sizeof b, p)) out = b;
    pclose(p);
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

}  // namespace

std::vector<std::string> buildFlagNotes() {
  std::vector<std::string> notes{std::string("ours: ") + PONYHOP_BUILD_FLAGS +
                                 "; the peer modules (our glue code) are compiled with the same flags"};
  struct Package {
    const char* engine;
    const char* package;
    const char* pc;  // pkg-config module, or ""
  };
  constexpr Package kPackages[] = {{"MuJoCo", "libmujoco-dev", ""},
                                   {"Bullet", "libbullet-dev", "bullet-float64"},
                                   {"ODE", "libode-dev", "ode"},
                                   {"DART", "libdart-dev", "dart"}};
  for (const Package& p : kPackages) {
    const std::string version = firstLine(std::string("dpkg-query -W -f='${Version}' ") + p.package);
    if (version.empty()) continue;
    std::string line = std::string(p.engine) + ": Debian package " + p.package + " " + version;
    if (p.pc[0]) {
      const std::string cflags = firstLine(std::string("pkg-config --cflags ") + p.pc);
      line += ", pkg-config " + std::string(p.pc) + " --cflags '" + cflags + "'";
    }
    notes.push_back(line);
  }
  // Without -ffile-prefix-map=<the current folder>=.: it names where the bench ran, not a flag.
  std::string debian;
  std::istringstream words(firstLine("dpkg-buildflags --get CXXFLAGS"));
  for (std::string w; words >> w;) {
    if (w.rfind("-ffile-prefix-map", 0) != 0) debian += (debian.empty() ? "" : " ") + w;
  }
  notes.push_back(
      "the engines' libraries record no compiler flags (no .comment section, no debug info): Debian "
      "builds its packages with dpkg-buildflags' defaults unless a package's rules override them" +
      (debian.empty() ? std::string() : " (here: CXXFLAGS '" + debian + "')"));
  return notes;
}

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
    m.v.push_back(b.v);
    m.w.push_back(b.w);
    m.radius.push_back(ch.radii[i]);
  }
  // A moving anchor (the bench's shake case): the kinematic anchor body's prescribed motion.
  const Scene& scene = sim.scene();
  if (scene.anchor && scene.anchor->motion != AnchorMotion::Fixed && sim.anchorBody() >= 0) {
    const KinematicMotion motion = sim.world().body(sim.anchorBody()).motion;
    const Eigen::Vector3d offset = m.anchor - motion(0.0).x;  // the anchor point in the anchor body (zero)
    m.motion = [motion, offset](double t) {
      const KinematicState k = motion(t);
      return PeerAnchorState{k.x + offset, k.v, k.a};
    };
  }
  return m;
}

PeerFourBar peerFourBarOf(const Sim& sim) {
  const Scene& scene = sim.scene();
  if (!scene.chain || scene.chain->links != 3 || scene.chain->hinge.norm() == 0.0 || scene.joints.size() != 1 ||
      !scene.chains.empty()) {
    throw std::runtime_error("the peers' four-bar needs one chain of three links on a root hinge and one joint");
  }
  PeerFourBar f;
  f.chain = peerChainOf(sim);
  f.axis = scene.chain->hinge.normalized();
  f.ground = sim.chain()->bottom(sim.world(), 2);
  f.speed = scene.chain->servo.speed;
  f.stiffness = scene.chain->servo.stiffness;
  f.damping = scene.chain->servo.damping;
  return f;
}

RunResult benchPeerRun(const Peer& peer, const PeerChain& chain, double dt, double horizon, int repeats,
                       double long_duration, const Trajectory& reference, double e_start, bool conservative) {
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
  double drift = 0.0, joint = 0.0;
  Eigen::Vector3d prev = s.tip();
  std::vector<PeerLink> links;
  bool ok = true;
  for (long i = n + 1; i <= total; ++i) {
    s.step();
    if (i % sample != 0) continue;
    if (!(ok = s.finite())) break;
    if (conservative) drift = std::max(drift, std::abs(s.energy() - e0));
    // The joints, on every case as ours (bench_run.cpp): a long run whose joints come apart by
    // more than a centimetre is no choice, whichever engine took it.
    s.links(links);
    joint = std::max(joint, peerJointError(chain, links, s.time()));
    const Eigen::Vector3d p = s.tip();
    r.max_speed = std::max(r.max_speed, (p - prev).norm() / (sample * dt));
    prev = p;
  }
  r.long_reached = s.time();
  if (conservative) {
    r.energy_drift = drift;
    r.energy_rel = std::abs(e_start) > 0.0 ? drift / std::abs(e_start) : drift;
  }
  r.joint_drift = joint;
  char why[160] = "";
  if (!ok) {
    r.long_status = "stopped";
    r.long_reason = peer.name + "'s state became non-finite or ran away";
  } else if (joint > 1e-2 || r.max_speed > 100.0 || (conservative && r.energy_rel > 1.0)) {
    // Bounded as ours are (bench_run.cpp, the same order): joints held to a centimetre, the tip
    // slower than 100 m/s, and a conservative chain's energy within its own size.
    if (joint > 1e-2)
      std::snprintf(why, sizeof why, "joint error %.3g m > 1 cm", joint);
    else if (r.max_speed > 100.0)
      std::snprintf(why, sizeof why, "speed %.3g m/s > 100 m/s", r.max_speed);
    else
      std::snprintf(why, sizeof why, "energy drift beyond E0");
    r.long_status = "unbounded";
    r.long_reason = why;
  }
  return r;
}

double peerJointError(const PeerChain& chain, const std::vector<PeerLink>& links, double t) {
  double worst = 0.0;
  Eigen::Vector3d above = chain.anchorAt(t).x;  // the end the next link's top must meet
  for (const PeerLink& l : links) {
    const Eigen::Vector3d half = l.q.normalized() * Eigen::Vector3d(0.0, 0.0, 0.5 * chain.length);
    worst = std::max(worst, (l.x + half - above).norm());
    above = l.x - half;
  }
  return worst;
}

namespace {

class PeerSubject final : public ScalingSubject {
 public:
  // The PeerSim keeps a reference to the chain it was made from: made here, from chain_.
  static std::unique_ptr<PeerSubject> make(const Peer& peer, PeerChain chain, std::string& error) {
    auto subject = std::unique_ptr<PeerSubject>(new PeerSubject(peer, std::move(chain)));
    subject->sim_ = peer.make(subject->chain_, kBenchGrid, error);
    if (!subject->sim_) return nullptr;
    return subject;
  }
  bool step() override {
    sim_->step();
    return true;
  }
  bool ok() override { return sim_->finite(); }
  double jointError() override {
    sim_->links(links_);
    return peerJointError(chain_, links_, sim_->time());
  }
  std::string why() const override {
    char b[160];
    std::snprintf(b, sizeof b, "t = %.6g s: %s's state became non-finite or ran away", sim_->time(), name_.c_str());
    return b;
  }
  double time() const override { return sim_->time(); }

 private:
  PeerSubject(const Peer& peer, PeerChain chain) : name_(peer.name), chain_(std::move(chain)) {}
  std::string name_;
  PeerChain chain_;
  std::unique_ptr<PeerSim> sim_;
  std::vector<PeerLink> links_;
};

}  // namespace

ScalingConfig peerScalingConfig(const Peer& peer, const std::string& scene) {
  ScalingConfig c;
  c.name = peer.name;
  c.peer = true;
  // ODE works in maximal coordinates and pulls its joints back (ERP); the others' joints hold by
  // construction.
  c.drift = peer.name.rfind("ode/", 0) == 0 ? "peer: ERP 0.2 (joint error correction)" : "peer: reduced coordinates";
  c.make = [peer, scene](int links, std::string& error) -> std::unique_ptr<ScalingSubject> {
    return PeerSubject::make(peer, peerChainOf(Sim(loadScene(scene, scalingOverrides(links)))), error);
  };
  return c;
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
    const auto entry = reinterpret_cast<decltype(&ponyhop_peers_v3)>(dlsym(handle, kPeerEntry));
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

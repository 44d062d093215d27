// Compiled only when CMake found MuJoCo (app/CMakeLists.txt defines PONYHOP_HAVE_MUJOCO).
#include "app/bench_mujoco.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <unistd.h>

namespace ponyhop {
namespace {

using Clock = std::chrono::steady_clock;

std::string vec(const Eigen::Vector3d& v) {
  char b[96];
  std::snprintf(b, sizeof b, "%.17g %.17g %.17g", v.x(), v.y(), v.z());
  return b;
}

std::string quat(const Eigen::Quaterniond& q) {  // MuJoCo: w x y z
  char b[128];
  std::snprintf(b, sizeof b, "%.17g %.17g %.17g %.17g", q.w(), q.x(), q.y(), q.z());
  return b;
}

struct Model {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::string error;
  ~Model() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }
};

// mj_loadXML reads a file: the text goes to a temporary file that is removed right after.
std::unique_ptr<Model> load(const std::string& xml) {
  auto model = std::make_unique<Model>();
  static int counter = 0;
  const auto path = std::filesystem::temp_directory_path() /
                    ("ponyhop_bench_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".xml");
  {
    std::ofstream f(path);
    f << xml;
  }
  char err[1000] = "";
  model->m = mj_loadXML(path.c_str(), nullptr, err, sizeof err);
  std::error_code ec;
  std::filesystem::remove(path, ec);
  if (!model->m) {
    model->error = std::string("MuJoCo could not load the chain: ") + err;
    return model;
  }
  model->d = mj_makeData(model->m);
  return model;
}

Eigen::Vector3d tip(const Model& s) {
  const mjtNum* p = s.d->site_xpos;  // site 0: the free end of the last link
  return {p[0], p[1], p[2]};
}

bool finite(const Model& s) {
  for (int i = 0; i < s.m->nq; ++i) {
    if (!std::isfinite(s.d->qpos[i]) || std::abs(s.d->qpos[i]) > 1e10) return false;
  }
  for (int i = 0; i < s.m->nv; ++i) {
    if (!std::isfinite(s.d->qvel[i]) || std::abs(s.d->qvel[i]) > 1e10) return false;
  }
  return s.d->warning[mjWARN_BADQACC].number == 0;
}

}  // namespace

std::string mujocoVersion() { return mj_versionString(); }

std::string mujocoChainXml(const MujocoChain& c, const std::string& integrator, double dt) {
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"ponyhop chain\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << "  <option timestep=\"" << dt << "\" gravity=\"" << vec(c.gravity) << "\" integrator=\"" << integrator
    << "\">\n"
    << "    <flag contact=\"disable\" energy=\"enable\"/>\n"
    << "  </option>\n"
    << "  <worldbody>\n";
  // Body frame of link i: origin at its top end (the ball joint), axes as ponyhop's link frame;
  // centre of mass at (0, 0, -L/2), the next link's top end at (0, 0, -L).
  const size_t n = c.mass.size();
  std::string indent = "    ";
  for (size_t i = 0; i < n; ++i) {
    if (i == 0) {
      x << indent << "<body name=\"link0\" pos=\"" << vec(c.anchor) << "\" quat=\"" << quat(c.q[0]) << "\">\n";
    } else {
      const Eigen::Quaterniond rel = c.q[i - 1].conjugate() * c.q[i];
      x << indent << "<body name=\"link" << i << "\" pos=\"0 0 " << -c.length << "\" quat=\"" << quat(rel)
        << "\">\n";
    }
    x << indent << "  <joint type=\"ball\" pos=\"0 0 0\" damping=\"0\" armature=\"0\"/>\n"
      << indent << "  <inertial pos=\"0 0 " << -0.5 * c.length << "\" mass=\"" << c.mass[i] << "\" diaginertia=\""
      << vec(c.inertia[i]) << "\"/>\n"
      << indent << "  <geom type=\"cylinder\" fromto=\"0 0 0 0 0 " << -c.length << "\" size=\"" << c.radius[i]
      << "\" contype=\"0\" conaffinity=\"0\"/>\n";
    if (i + 1 == n) x << indent << "  <site name=\"tip\" pos=\"0 0 " << -c.length << "\"/>\n";
    indent += "  ";
  }
  for (size_t i = n; i-- > 0;) {
    indent.resize(indent.size() - 2);
    x << indent << "</body>\n";
  }
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

RunResult benchMujocoRun(const MujocoChain& chain, const std::string& integrator, double dt, double horizon,
                         int repeats, double long_duration, const Trajectory& reference, double e_start) {
  RunResult r;
  const std::string xml = mujocoChainXml(chain, integrator, dt);
  const long n = std::lround(horizon / dt);
  const long every = std::max(1L, std::lround(kBenchGrid / dt));
  r.steps = n;
  Trajectory traj;
  traj.stride = every * dt;
  std::vector<double> per_step;
  std::unique_ptr<Model> first;
  for (int rep = 0; rep < std::max(1, repeats); ++rep) {
    auto s = load(xml);
    if (!s->m) {
      r.status = "failed";
      r.reason = s->error;
      return r;
    }
    mj_forward(s->m, s->d);
    if (rep == 0) traj.p.push_back(tip(*s));
    Clock::duration total{};
    long taken = 0;
    bool ok = true;
    for (long i = 1; i <= n; ++i) {
      const auto t0 = Clock::now();
      mj_step(s->m, s->d);
      total += Clock::now() - t0;
      ++taken;
      if (!(ok = finite(*s))) break;
      if (rep == 0 && i % every == 0) {
        mj_kinematics(s->m, s->d);  // site positions at the new state (mj_step leaves the old ones)
        traj.p.push_back(tip(*s));
      }
    }
    per_step.push_back(std::chrono::duration<double>(total).count() / std::max(1L, taken));
    if (!ok) {
      char b[160];
      std::snprintf(b, sizeof b, "t = %.6g s: MuJoCo's state became non-finite or ran away (%s, dt %.6g s)",
                    s->d->time, integrator.c_str(), dt);
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
  // Long run: energy drift (MuJoCo's own energy, against its value at t = 0), joints exact.
  Model& s = *first;
  const long total = std::lround(long_duration / dt);
  const long sample = std::max(1L, std::lround((1.0 / 240.0) / dt));
  auto fresh = load(xml);
  mj_forward(fresh->m, fresh->d);
  const double e0 = fresh->d->energy[0] + fresh->d->energy[1];
  fresh.reset();
  double drift = 0.0;
  Eigen::Vector3d prev = tip(s);
  bool ok = true;
  for (long i = n + 1; i <= total; ++i) {
    mj_step(s.m, s.d);
    if (!(ok = finite(s))) break;
    if (i % sample == 0) {
      mj_forward(s.m, s.d);  // energy and sites at the new state
      drift = std::max(drift, std::abs(s.d->energy[0] + s.d->energy[1] - e0));
      const Eigen::Vector3d p = tip(s);
      r.max_speed = std::max(r.max_speed, (p - prev).norm() / (sample * dt));
      prev = p;
    }
  }
  r.long_reached = s.d->time;
  r.energy_drift = drift;
  r.energy_rel = std::abs(e_start) > 0.0 ? drift / std::abs(e_start) : drift;
  if (!ok) {
    r.long_status = "stopped";
    r.long_reason = "MuJoCo's state became non-finite or ran away";
  } else if (r.energy_rel > 1.0) {
    r.long_status = "unbounded";
    r.long_reason = "energy drift beyond E0";
  }
  return r;
}

}  // namespace ponyhop

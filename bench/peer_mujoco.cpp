// The module ponyhop-peer-mujoco.so, built only when CMake finds MuJoCo (libmujoco-dev;
// bench/CMakeLists.txt).
//
// A moving anchor (the shake case) is a body on three slide joints (x, y, z) from the world, the
// chain's link 0 its child, driven exactly: MuJoCo calls mjcb_control in every evaluation of the
// dynamics (each of RK4's four stages, at the stage's time), after the mass matrix is factored and
// the bias and passive forces are known, so the callback sets the slide joints' qfrc_applied to
// the force f that gives them the wanted acceleration: qacc = M^-1 (qfrc_passive - qfrc_bias + f),
// f = A^-1 (target - qacc0), qacc0 by mj_solveM, A (the slide rows and columns of M^-1) from the
// root block of MuJoCo's factor of M. RK4: the target
// is the path's acceleration at the stage's time. Euler (semi-implicit: the new velocity moves the
// positions): the target takes the anchor's velocity to the secant velocity to the path's point at
// t + dt (PeerChain::secant), so the anchor is on the path at every step's end.
// A mocap body would not do: MuJoCo reads only a mocap body's pose, its velocity and acceleration
// are taken as zero in the dynamics (mj_comVel and the bias forces), so a chain hung from a mocap
// body is carried rigidly from pose to pose and feels none of the anchor's acceleration.
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "bench/peer.h"

namespace ponyhop {
namespace {

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

bool finite(const Model& s) {
  for (int i = 0; i < s.m->nq; ++i) {
    if (!std::isfinite(s.d->qpos[i]) || std::abs(s.d->qpos[i]) > 1e10) return false;
  }
  for (int i = 0; i < s.m->nv; ++i) {
    if (!std::isfinite(s.d->qvel[i]) || std::abs(s.d->qvel[i]) > 1e10) return false;
  }
  return s.d->warning[mjWARN_BADQACC].number == 0;
}

// The MJCF model's opening up to <worldbody>: integrator "Euler" or "RK4", timestep dt.
void mujocoHeader(std::ostringstream& x, const PeerChain& c, const std::string& integrator, double dt) {
  x.precision(17);
  x << "<mujoco model=\"ponyhop chain\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << "  <option timestep=\"" << dt << "\" gravity=\"" << vec(c.gravity) << "\" integrator=\"" << integrator << "\">\n"
    << "    <flag contact=\"disable\" energy=\"enable\"/>\n"
    << "  </option>\n"
    << "  <worldbody>\n";
}

// A link's inertial element, its centre of mass at `com` in the body frame.
std::string inertial(const PeerChain& c, size_t i, const Eigen::Vector3d& com) {
  char m[32];
  std::snprintf(m, sizeof m, "%.17g", c.mass[i]);
  return "<inertial pos=\"" + vec(com) + "\" mass=\"" + m + "\" diaginertia=\"" + vec(c.inertia[i]) + "\"/>";
}

// The MJCF text of the chain with integrator "Euler" or "RK4" and timestep dt.
std::string mujocoChainXml(const PeerChain& c, const std::string& integrator, double dt) {
  std::ostringstream x;
  mujocoHeader(x, c, integrator, dt);
  // Body frame of link i: origin at its top end (the ball joint), axes as ponyhop's link frame;
  // centre of mass at (0, 0, -L/2), the next link's top end at (0, 0, -L).
  const size_t n = c.mass.size();
  std::string indent = "    ";
  if (c.moving()) {
    // The moving anchor: three slide joints (qpos 0..2 are the anchor's position less `anchor`).
    x << indent << "<body name=\"anchor\" pos=\"" << vec(c.anchor) << "\">\n"
      << indent << "  <joint name=\"ax\" type=\"slide\" axis=\"1 0 0\"/>\n"
      << indent << "  <joint name=\"ay\" type=\"slide\" axis=\"0 1 0\"/>\n"
      << indent << "  <joint name=\"az\" type=\"slide\" axis=\"0 0 1\"/>\n"
      << indent << "  <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.001 0.001 0.001\"/>\n";
    indent += "  ";
  }
  for (size_t i = 0; i < n; ++i) {
    if (i == 0) {
      x << indent << "<body name=\"link0\" pos=\"" << vec(c.moving() ? Eigen::Vector3d::Zero() : c.anchor)
        << "\" quat=\"" << quat(c.q[0]) << "\">\n";
    } else {
      const Eigen::Quaterniond rel = c.q[i - 1].conjugate() * c.q[i];
      x << indent << "<body name=\"link" << i << "\" pos=\"0 0 " << -c.length << "\" quat=\"" << quat(rel) << "\">\n";
    }
    x << indent << "  <joint type=\"ball\" pos=\"0 0 0\" damping=\"0\" armature=\"0\"/>\n"
      << indent << "  " << inertial(c, i, {0.0, 0.0, -0.5 * c.length}) << "\n"
      << indent << "  <geom type=\"cylinder\" fromto=\"0 0 0 0 0 " << -c.length << "\" size=\"" << c.radius[i]
      << "\" contype=\"0\" conaffinity=\"0\"/>\n";
    if (i + 1 == n) x << indent << "  <site name=\"tip\" pos=\"0 0 " << -c.length << "\"/>\n";
    indent += "  ";
  }
  for (size_t i = n + (c.moving() ? 1 : 0); i-- > 0;) {
    indent.resize(indent.size() - 2);
    x << indent << "</body>\n";
  }
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

// The MJCF text of the four-bar (bench/peer.h, PeerFourBar): the crank's body frame has its origin
// at the crank's pivot (the anchor), the coupler's at its top end, as the chain's; the follower's
// is its link frame (centre of mass at the origin), its hinge at its bottom end. The closure is a
// `connect` equality with MuJoCo's default solref and solimp: the coupler's bottom end, (0, 0, -L)
// in its frame, held to the follower point that coincides with it at qpos0 (the t = 0 pose).
std::string mujocoFourBarXml(const PeerFourBar& f, const std::string& integrator, double dt) {
  const PeerChain& c = f.chain;
  std::ostringstream x;
  mujocoHeader(x, c, integrator, dt);
  const Eigen::Vector3d half(0.0, 0.0, 0.5 * c.length);
  const Eigen::Quaterniond rel = c.q[0].conjugate() * c.q[1];
  x << "    <body name=\"crank\" pos=\"" << vec(c.anchor) << "\" quat=\"" << quat(c.q[0]) << "\">\n"
    << "      <joint type=\"hinge\" pos=\"0 0 0\" axis=\"" << vec(c.q[0].conjugate() * f.axis) << "\"/>\n"
    << "      " << inertial(c, 0, -half) << "\n"
    << "      <body name=\"coupler\" pos=\"" << vec(-2.0 * half) << "\" quat=\"" << quat(rel) << "\">\n"
    << "        <joint type=\"ball\" pos=\"0 0 0\"/>\n"
    << "        " << inertial(c, 1, -half) << "\n"
    << "      </body>\n"
    << "    </body>\n"
    << "    <body name=\"follower\" pos=\"" << vec(f.ground + c.q[2] * half) << "\" quat=\"" << quat(c.q[2]) << "\">\n"
    << "      <joint type=\"hinge\" pos=\"" << vec(-half) << "\" axis=\"" << vec(c.q[2].conjugate() * f.axis)
    << "\"/>\n"
    << "      " << inertial(c, 2, Eigen::Vector3d::Zero()) << "\n"
    << "    </body>\n"
    << "  </worldbody>\n"
    << "  <equality>\n"
    << "    <connect body1=\"coupler\" body2=\"follower\" anchor=\"" << vec(-2.0 * half) << "\"/>\n"
    << "  </equality>\n"
    << "</mujoco>\n";
  return x.str();
}

class MujocoSim;
MujocoSim* g_driving = nullptr;  // the sim whose mj_step is running, when its anchor moves
void driveAnchor(const mjModel* m, mjData* d);

class MujocoSim final : public PeerSim {
 public:
  // four_bar: the four-bar whose crank the servo turns (its hinge is dof 0), or nullptr.
  MujocoSim(const PeerChain& chain, std::unique_ptr<Model> model, const PeerFourBar* four_bar = nullptr)
      : PeerSim(chain), s_(std::move(model)), four_bar_(four_bar) {
    if (!four_bar_) {
      // The t = 0 velocities: the anchor's (slides), each ball joint's relative angular velocity in
      // its body's frame (MuJoCo's ball joint velocity).
      int v = 0;
      if (chain.moving()) {
        const Eigen::Vector3d va = chain.anchorAt(0.0).v;
        for (int k = 0; k < 3; ++k) s_->d->qvel[v++] = va[k];
        first_link_ = 2;
        solve_.resize(size_t(s_->m->nv));
        rhs_.resize(solve_.size());
        mjcb_control = &driveAnchor;
      }
      for (size_t i = 0; i < chain.mass.size(); ++i) {
        const Eigen::Vector3d w = chain.relativeW0(i);
        for (int k = 0; k < 3; ++k) s_->d->qvel[v++] = w[k];
      }
    }
    mj_forward(s_->m, s_->d);
  }
  void step() override {
    const double t = s_->d->time;
    if (four_bar_ && four_bar_->servo()) {
      links(scratch_);
      s_->d->qfrc_applied[0] = four_bar_->servoTorque(scratch_[0], t);
    }
    g_driving = first_link_ == 2 ? this : nullptr;
    mj_step(s_->m, s_->d);
    g_driving = nullptr;
    // When an acceleration goes bad (non-finite or above 1e10), mj_step warns (mjWARN_BADQACC) and
    // resets the state to the model's start, time 0, and goes on from there: the run ended at this
    // step (finite() says so), not at the time the reset state shows.
    if (stopped_ < 0.0 && s_->d->warning[mjWARN_BADQACC].number > 0) stopped_ = t + s_->m->opt.timestep;
  }
  double time() const override { return stopped_ >= 0.0 ? stopped_ : s_->d->time; }
  // Body i + 1 is link i (body 0 is the world); its inertial frame is the link's centre.
  void links(std::vector<PeerLink>& out) override {
    mj_forward(s_->m, s_->d);  // kinematics, velocities and energy at the new state
    out.resize(chain_.mass.size());
    for (size_t i = 0; i < out.size(); ++i) {
      const int b = static_cast<int>(i) + first_link_;
      const mjtNum* x = s_->d->xipos + 3 * b;
      const mjtNum* q = s_->d->xquat + 4 * b;
      mjtNum vel[6];
      mj_objectVelocity(s_->m, s_->d, mjOBJ_BODY, b, vel, 0);
      out[i].x = {x[0], x[1], x[2]};
      out[i].q = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
      out[i].w = {vel[0], vel[1], vel[2]};
      out[i].v = {vel[3], vel[4], vel[5]};
    }
  }
  double energy() override {
    if (first_link_ == 2) return PeerSim::energy();  // the links' (MuJoCo's would count the anchor body)
    mj_forward(s_->m, s_->d);
    return s_->d->energy[0] + s_->d->energy[1];
  }
  bool finite() override { return ponyhop::finite(*s_); }

  // mjcb_control, in every evaluation of the dynamics while this sim steps (see the top): the
  // slide joints' forces that give the anchor its prescribed acceleration.
  void drive(const mjModel* m, mjData* d) {
    const int nv = m->nv;
    // qacc0: the acceleration without f (one solve with the factored M).
    mjtNum* y = rhs_.data();
    mjtNum* x = solve_.data();
    for (int i = 0; i < nv; ++i) y[i] = d->qfrc_passive[i] - d->qfrc_bias[i];
    mj_solveM(m, d, x, y, 1);
    const Eigen::Vector3d acc0(x[0], x[1], x[2]);
    // A = (M^-1)_ss from the factor's root block: MuJoCo factors M = L' D L, L unit lower
    // triangular with L(i, j) != 0 only for j an ancestor of i, stored in qLD as M is (dof i at
    // dof_Madr[i]: D(i), then L(i, parent), L(i, grandparent), ...). L^-1 is lower triangular, so
    // the slides' rows of M^-1 = L^-1 D^-1 L^-T involve only the 3 x 3 root block:
    // A = Lss^-1 Dss^-1 Lss^-T (the slides are dofs 0, 1, 2, each the parent of the next).
    Eigen::Matrix3d l = Eigen::Matrix3d::Identity();
    l(1, 0) = d->qLD[m->dof_Madr[1] + 1];
    l(2, 1) = d->qLD[m->dof_Madr[2] + 1];
    l(2, 0) = d->qLD[m->dof_Madr[2] + 2];
    const Eigen::Matrix3d li = l.triangularView<Eigen::UnitLower>().solve(Eigen::Matrix3d::Identity());
    const Eigen::Matrix3d a =
        li * Eigen::Vector3d(d->qLDiagInv[0], d->qLDiagInv[1], d->qLDiagInv[2]).asDiagonal() * li.transpose();
    const double t = d->time, h = m->opt.timestep;
    const Eigen::Vector3d vel(d->qvel[0], d->qvel[1], d->qvel[2]);
    Eigen::Vector3d target;
    if (m->opt.integrator == mjINT_RK4) {
      target = chain_.anchorAt(t).a;
    } else {  // semi-implicit Euler: to the secant velocity from where the anchor is now
      const Eigen::Vector3d pos = chain_.anchor + Eigen::Vector3d(d->qpos[0], d->qpos[1], d->qpos[2]);
      target = ((chain_.anchorAt(t + h).x - pos) / h - vel) / h;
    }
    const Eigen::Vector3d f = a.ldlt().solve(target - acc0);
    for (int k = 0; k < 3; ++k) d->qfrc_applied[k] = f[k];
  }

 private:
  int first_link_ = 1;               // body index of link 0 (body 0 is the world; 1 the moving anchor)
  std::vector<mjtNum> rhs_, solve_;  // mj_solveM's right-hand sides and solutions (the moving anchor)
  std::unique_ptr<Model> s_;
  const PeerFourBar* four_bar_;
  double stopped_ = -1.0;  // s, when MuJoCo reset the state after a bad acceleration
};

void driveAnchor(const mjModel* m, mjData* d) {
  if (g_driving) g_driving->drive(m, d);
}

Peer mujocoPeer(const std::string& integrator) {
  Peer p;
  p.name = "mujoco/" + integrator;
  p.version = std::string("MuJoCo ") + mj_versionString() +
              ": Euler = its semi-implicit Euler, RK4; ball joints, exact masses and inertias, no contact, damping "
              "or armature; a shaking anchor on three slide joints forced to the path's acceleration (mjcb_control)";
  p.make = [integrator](const PeerChain& chain, double dt, std::string& error) -> std::unique_ptr<PeerSim> {
    auto model = load(mujocoChainXml(chain, integrator, dt));
    if (!model->m) {
      error = model->error;
      return nullptr;
    }
    if (chain.moving() &&
        (model->m->dof_parentid[0] != -1 || model->m->dof_parentid[1] != 0 || model->m->dof_parentid[2] != 1)) {
      error = "MuJoCo ordered the anchor's slide joints otherwise than the drive reads its factor";
      return nullptr;
    }
    return std::make_unique<MujocoSim>(chain, std::move(model));
  };
  p.four_bar_version = "MuJoCo " + std::string(mj_versionString()) +
                       ": two trees (crank + coupler, follower) closed by a `connect` equality, default solref "
                       "(0.02, 1) and solimp; the servo as qfrc_applied on the crank's hinge";
  p.makeFourBar = [integrator](const PeerFourBar& f, double dt, std::string& error) -> std::unique_ptr<PeerSim> {
    auto model = load(mujocoFourBarXml(f, integrator, dt));
    if (!model->m) {
      error = model->error;
      return nullptr;
    }
    return std::make_unique<MujocoSim>(f.chain, std::move(model), &f);
  };
  return p;
}

}  // namespace
}  // namespace ponyhop

extern "C" void ponyhop_peers_v3(std::vector<ponyhop::Peer>* out) {
  out->push_back(ponyhop::mujocoPeer("Euler"));
  out->push_back(ponyhop::mujocoPeer("RK4"));
}

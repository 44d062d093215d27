#include "physics/models/keyframes.h"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "physics/sparse_lu.h"

namespace ponyhop {

namespace {

constexpr double kPi = std::numbers::pi;
using Rows6 = Eigen::Matrix<double, Eigen::Dynamic, 6>;  // per knot: position (3), rotation vector (3)

std::string fmt(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

// ---------------------------------------------------------------------------------------------
// A second-order jet: f(t), f'(t), f''(t). Pushing jets through a formula gives the exact first
// and second time derivatives of the result (forward-mode differentiation, truncated at order 2).
struct Jet {
  double v = 0, d = 0, dd = 0;
};
Jet operator+(const Jet& a, const Jet& b) { return {a.v + b.v, a.d + b.d, a.dd + b.dd}; }
// (ab)' = a'b + ab', (ab)'' = a''b + 2a'b' + ab''
Jet operator*(const Jet& a, const Jet& b) {
  return {a.v * b.v, a.d * b.v + a.v * b.d, a.dd * b.v + 2.0 * a.d * b.d + a.v * b.dd};
}

// A scalar function with its first two derivatives at one point.
struct F012 {
  double f, f1, f2;
};
// Chain rule for g(t) = f(x(t)): g' = f1 x', g'' = f2 x'^2 + f1 x''.
Jet apply(const F012& f, const Jet& x) { return {f.f, f.f1 * x.d, f.f2 * x.d * x.d + f.f1 * x.dd}; }

// The exponential map written in x = |r|^2 so that it is smooth (analytic) at r = 0:
//   q = (C(x), S(x) r),  C(x) = cos(sqrt(x)/2),  S(x) = sin(sqrt(x)/2) / sqrt(x).
// S(x) = 1/2 - x/48 + x^2/3840 - x^3/645120 + x^4/185794560 - ...   (sin series in u = sqrt(x)/2)
// S'(x) = (th cos(th/2)/2 - sin(th/2)) / (2 th^3),  th = sqrt(x)
// S''(x) = (-th^2 sin(th/2)/4 - 3 th cos(th/2)/2 + 3 sin(th/2)) / (4 th^5)
// C'(x) = -S(x)/4,  C''(x) = -S'(x)/4.
// The closed forms cancel catastrophically as th -> 0; below th = 0.1 the series (truncation
// error < 1e-15 relative there) is used instead.
F012 sincHalf(double x) {
  if (x < 1e-2) {
    return {0.5 + x * (-1.0 / 48 + x * (1.0 / 3840 + x * (-1.0 / 645120 + x / 185794560))),
            -1.0 / 48 + x * (2.0 / 3840 + x * (-3.0 / 645120 + x * 4.0 / 185794560)),
            2.0 / 3840 + x * (-6.0 / 645120 + x * 12.0 / 185794560)};
  }
  const double th = std::sqrt(x), sh = std::sin(0.5 * th), ch = std::cos(0.5 * th);
  const double th2 = th * th, th3 = th2 * th;
  return {sh / th, (0.5 * th * ch - sh) / (2.0 * th3),
          (-0.25 * th2 * sh - 1.5 * th * ch + 3.0 * sh) / (4.0 * th3 * th2)};
}
F012 cosHalf(double x) {
  const F012 s = sincHalf(x);
  return {std::cos(0.5 * std::sqrt(x)), -0.25 * s.f, -0.25 * s.f1};
}
double apply1(F012 (*f)(double), double x) { return f(x).f; }
Jet apply1(F012 (*f)(double), const Jet& x) { return apply(f(x.v), x); }

template <class S>
struct Quat {
  S w, x, y, z;
};
// One formula for values (S = double) and for values with derivatives (S = Jet).
template <class S>
Quat<S> expRv(const S& rx, const S& ry, const S& rz) {
  const S x2 = rx * rx + ry * ry + rz * rz;
  const S c = apply1(cosHalf, x2);
  const S s = apply1(sincHalf, x2);
  return {c, s * rx, s * ry, s * rz};
}

Eigen::Quaterniond expRv(const Eigen::Vector3d& r) {
  const Quat<double> q = expRv(r.x(), r.y(), r.z());
  return Eigen::Quaterniond(q.w, q.x, q.y, q.z);
}

// Rotation vector of a unit quaternion, angle in [0, pi].
Eigen::Vector3d logQuat(Eigen::Quaterniond q) {
  if (q.w() < 0) q.coeffs() *= -1.0;
  const double s = q.vec().norm();
  if (s == 0.0) return Eigen::Vector3d::Zero();
  return q.vec() * (2.0 * std::atan2(s, q.w()) / s);
}

// Of the rotation vectors (|r| + 2 pi k) r/|r| (k integer) that all give the same rotation as r,
// the one nearest `prev`. Keeps a spin continuous: 350 deg after 340 deg, not -10 deg.
Eigen::Vector3d unwrapNear(const Eigen::Vector3d& r, const Eigen::Vector3d& prev) {
  const double th = r.norm();
  if (th < 1e-12) {  // identity: any axis; take prev's
    const double p = prev.norm();
    if (p < 1e-12) return r;
    return r + (2.0 * kPi * std::round(p / (2.0 * kPi))) * (prev / p);
  }
  const Eigen::Vector3d n = r / th;
  const double k = std::round((n.dot(prev) - th) / (2.0 * kPi));
  return (th + 2.0 * kPi * k) * n;
}

bool finite3(const Eigen::Vector3d& v) { return v.allFinite(); }

// ---------------------------------------------------------------------------------------------
// C2 cubic spline on knots s_0..s_m with values y_j and second derivatives M_j. On [s_j, s_j+1],
// h = s_j+1 - s_j, A = (s_j+1 - t)/h, B = (t - s_j)/h:
//   S(t)   = A y_j + B y_j+1 + ((A^3 - A) M_j + (B^3 - B) M_j+1) h^2/6
//   S'(t)  = (y_j+1 - y_j)/h + (-(3A^2 - 1) M_j + (3B^2 - 1) M_j+1) h/6
//   S''(t) = A M_j + B M_j+1
// S' continuous at an inner knot j (h_a = s_j - s_j-1, h_b = s_j+1 - s_j):
//   h_a M_j-1 + 2 (h_a + h_b) M_j + h_b M_j+1 = 6 ((y_j+1 - y_j)/h_b - (y_j - y_j-1)/h_a).
// Loop: the same equation at every knot, indices modulo m (knot m is knot 0).
// Clamp: M_0 = M_m = 0 (zero acceleration at the ends) and S'(s_0) = S'(s_m) = 0 (zero
// velocity); the two extra equations are balanced by two knots whose values are unknowns.
// Solves for M (and the free values, written into Y).
bool solveSpline(const std::vector<double>& s, Rows6& Y, const std::vector<int>& freeKnots, bool periodic, Rows6& M) {
  const int m = static_cast<int>(s.size()) - 1;
  const int nM = periodic ? m : m + 1;
  const int n = nM + static_cast<int>(freeKnots.size());
  std::vector<int> freeIndex(s.size(), -1);
  for (size_t k = 0; k < freeKnots.size(); ++k) freeIndex[freeKnots[k]] = nM + static_cast<int>(k);
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 6);
  auto h = [&](int j) { return s[j + 1] - s[j]; };
  auto mIndex = [&](int j) { return periodic ? ((j % m) + m) % m : j; };
  auto addM = [&](int row, int j, double c) { trip.emplace_back(row, mIndex(j), c); };
  auto addY = [&](int row, int j, double c) {  // c * y_j on the left-hand side
    const int jj = periodic ? ((j % m) + m) % m : j;
    if (freeIndex[jj] >= 0) {
      trip.emplace_back(row, freeIndex[jj], c);
    } else {
      rhs.row(row) -= c * Y.row(jj);
    }
  };
  auto continuity = [&](int row, int j, double ha, double hb) {
    addM(row, j - 1, ha);
    addM(row, j, 2.0 * (ha + hb));
    addM(row, j + 1, hb);
    addY(row, j + 1, -6.0 / hb);
    addY(row, j, 6.0 / hb + 6.0 / ha);
    addY(row, j - 1, -6.0 / ha);
  };
  int row = 0;
  if (periodic) {
    for (int j = 0; j < m; ++j) continuity(row++, j, j == 0 ? h(m - 1) : h(j - 1), h(j));
  } else {
    for (int j = 1; j < m; ++j) continuity(row++, j, h(j - 1), h(j));
    addM(row++, 0, 1.0);  // M_0 = 0
    addM(row++, m, 1.0);  // M_m = 0
    // S'(s_0) = (y_1 - y_0)/h_0 - h_0 (2 M_0 + M_1)/6 = 0
    addY(row, 1, 1.0 / h(0));
    addY(row, 0, -1.0 / h(0));
    addM(row, 0, -h(0) / 3.0);
    addM(row, 1, -h(0) / 6.0);
    ++row;
    // S'(s_m) = (y_m - y_m-1)/h_m-1 + h_m-1 (M_m-1 + 2 M_m)/6 = 0
    addY(row, m, 1.0 / h(m - 1));
    addY(row, m - 1, -1.0 / h(m - 1));
    addM(row, m - 1, h(m - 1) / 6.0);
    addM(row, m, h(m - 1) / 3.0);
    ++row;
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(trip.begin(), trip.end());  // duplicates (small loops) are summed
  Eigen::MatrixXd z;
  if (sparseLuSolve(A, rhs, z) != SparseLuResult::Solved || !z.allFinite()) return false;
  M.resize(m + 1, 6);
  for (int j = 0; j <= m; ++j) M.row(j) = z.row(mIndex(j));
  for (size_t k = 0; k < freeKnots.size(); ++k) Y.row(freeKnots[k]) = z.row(nM + static_cast<int>(k));
  return true;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

struct KeyframeTrack::Data {
  LoopMode mode = LoopMode::Clamp;
  double speed = 1.0;
  double tFirst = 0, tLast = 0, period = 0;
  bool constant = false;
  Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity();
  std::vector<double> s;  // knots (clip time)
  Rows6 Y, M;             // values and second derivatives per knot
};

TrackOptions trackOptions(const AnimationParams& p) { return {p.mode, p.speed, p.amplitude}; }

Eigen::Quaterniond eulerDegToQuat(const Eigen::Vector3d& deg) {
  const Eigen::Vector3d r = deg * (kPi / 180.0);
  return Eigen::Quaterniond(Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()));
}

QuatJet expRotationVector(const Eigen::Vector3d& r, const Eigen::Vector3d& dr, const Eigen::Vector3d& ddr) {
  const Quat<Jet> q = expRv(Jet{r.x(), dr.x(), ddr.x()}, Jet{r.y(), dr.y(), ddr.y()}, Jet{r.z(), dr.z(), ddr.z()});
  return {Eigen::Quaterniond(q.w.v, q.x.v, q.y.v, q.z.v), Eigen::Quaterniond(q.w.d, q.x.d, q.y.d, q.z.d),
          Eigen::Quaterniond(q.w.dd, q.x.dd, q.y.dd, q.z.dd)};
}

Eigen::Vector3d angularVelocity(const QuatJet& j) { return 2.0 * (j.dq * j.q.conjugate()).vec(); }
Eigen::Vector3d angularAcceleration(const QuatJet& j) { return 2.0 * (j.ddq * j.q.conjugate()).vec(); }

// ---------------------------------------------------------------------------------------------

Status KeyframeTrack::fromKeyframes(const std::vector<Keyframe>& keys, const TrackOptions& options,
                                    KeyframeTrack& track) {
  std::vector<PoseSample> samples(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const std::string key = "key " + std::to_string(i);
    if (!finite3(keys[i].rotation)) return Status::error(key + ": field \"rotation\" is not a finite number");
    samples[i] = {keys[i].t, keys[i].position, eulerDegToQuat(keys[i].rotation)};
  }
  return fromSamples(samples, options, track);
}

Status KeyframeTrack::fromSamples(const std::vector<PoseSample>& in, const TrackOptions& opt, KeyframeTrack& track) {
  // ---- validate
  if (!std::isfinite(opt.speed) || opt.speed <= 0.0)
    return Status::error("field \"speed\" = " + fmt("%g", opt.speed) + " must be a finite number > 0");
  if (!std::isfinite(opt.amplitude) || opt.amplitude < 0.0)
    return Status::error("field \"amplitude\" = " + fmt("%g", opt.amplitude) + " must be a finite number >= 0");
  if (in.empty()) return Status::error("field \"keys\": at least one key is needed");
  for (size_t i = 0; i < in.size(); ++i) {
    const std::string key = "key " + std::to_string(i);
    if (!std::isfinite(in[i].t)) return Status::error(key + ": field \"t\" is not a finite number");
    if (!finite3(in[i].position)) return Status::error(key + ": field \"position\" is not a finite number");
    const double qn = in[i].rotation.coeffs().norm();
    if (!std::isfinite(qn) || qn < 1e-12)
      return Status::error(key + ": field \"rotation\" is not a finite, non-zero quaternion");
    if (i > 0 && !(in[i].t > in[i - 1].t))
      return Status::error(key + ": field \"t\" = " + fmt("%g", in[i].t) + " s must be greater than key " +
                           std::to_string(i - 1) + "'s t = " + fmt("%g", in[i - 1].t) +
                           " s (times must be strictly increasing)");
  }

  auto d = std::make_shared<Data>();
  d->mode = opt.mode;
  d->speed = opt.speed;
  d->tFirst = in.front().t;
  d->tLast = in.back().t;
  d->q0 = in.front().rotation.normalized();

  // ---- knots: key times, rotation vectors relative to the first key, unwrapped
  std::vector<double> t;
  std::vector<Eigen::Vector3d> p, r;
  for (size_t i = 0; i < in.size(); ++i) {
    const Eigen::Quaterniond rel = d->q0.conjugate() * in[i].rotation.normalized();
    t.push_back(in[i].t);
    p.push_back(in[i].position);
    r.push_back(i == 0 ? Eigen::Vector3d::Zero() : unwrapNear(logQuat(rel), r.back()));
  }
  const size_t n = t.size();
  if (opt.mode == LoopMode::Loop && n >= 2) {
    // Close the loop: a last key equal to the first (1e-6 m, 1e-6 rad) is the closing key;
    // otherwise the first key is repeated one mean key spacing after the last.
    const Eigen::Quaterniond qLast = in.back().rotation.normalized();
    const bool closes = (p.back() - p.front()).norm() < 1e-6 && d->q0.angularDistance(qLast) < 1e-6;
    if (!closes) {
      t.push_back(t.back() + (t.back() - t.front()) / static_cast<double>(n - 1));
      p.push_back(p.front());
      r.push_back(unwrapNear(Eigen::Vector3d::Zero(), r.back()));
    }
    // Periodic rotation vectors need r_last = r_0 = 0; a net full turn cannot loop seamlessly
    // in this chart (exp(r + 2 pi k n) != exp(r) for r not along n).
    if (r.back().norm() > 1e-6) {
      const Eigen::Vector3d axis = r.back().normalized();
      return Status::error("loop mode: the keys turn a net " + fmt("%.0f", r.back().norm() * 180.0 / kPi) +
                           " deg about (" + fmt("%.3g", axis.x()) + ", " + fmt("%.3g", axis.y()) + ", " +
                           fmt("%.3g", axis.z()) + ") from key 0 back to key 0; a looping clip must return to" +
                           " its first orientation without a full turn (use mode clamp, or key the turn back)");
    }
    p.back() = p.front();
    r.back().setZero();
  }
  // ---- amplitude: scale each key's offset from the first key
  for (size_t i = 0; i < t.size(); ++i) {
    p[i] = p.front() + opt.amplitude * (p[i] - p.front());
    r[i] *= opt.amplitude;
  }

  d->period = opt.mode == LoopMode::Loop && t.size() >= 2 ? t.back() - t.front() : 0.0;
  d->constant = in.size() == 1;
  if (d->constant) {
    d->s = {t[0]};
    d->Y.resize(1, 6);
    d->Y << p[0].transpose(), r[0].transpose();
    d->M = Rows6::Zero(1, 6);
    track.d_ = d;
    return {};
  }

  // ---- knots and free knots
  std::vector<int> freeKnots;
  std::vector<double>& s = d->s;
  std::vector<int> keyOfKnot;  // -1: free knot
  if (opt.mode == LoopMode::Loop) {
    s = t;
    keyOfKnot.resize(t.size());
    for (size_t i = 0; i < t.size(); ++i) keyOfKnot[i] = static_cast<int>(i);
  } else if (t.size() == 2) {
    s = {t[0], t[0] + (t[1] - t[0]) / 3.0, t[0] + 2.0 * (t[1] - t[0]) / 3.0, t[1]};
    keyOfKnot = {0, -1, -1, 1};
  } else {
    const size_t k = t.size();
    s.push_back(t[0]);
    keyOfKnot.push_back(0);
    s.push_back(0.5 * (t[0] + t[1]));
    keyOfKnot.push_back(-1);
    for (size_t i = 1; i + 1 < k; ++i) {
      s.push_back(t[i]);
      keyOfKnot.push_back(static_cast<int>(i));
    }
    s.push_back(0.5 * (t[k - 2] + t[k - 1]));
    keyOfKnot.push_back(-1);
    s.push_back(t[k - 1]);
    keyOfKnot.push_back(static_cast<int>(k - 1));
  }
  d->Y = Rows6::Zero(static_cast<Eigen::Index>(s.size()), 6);
  for (size_t j = 0; j < s.size(); ++j) {
    if (keyOfKnot[j] < 0) {
      freeKnots.push_back(static_cast<int>(j));
    } else {
      d->Y.row(j) << p[keyOfKnot[j]].transpose(), r[keyOfKnot[j]].transpose();
    }
  }
  if (!solveSpline(s, d->Y, freeKnots, opt.mode == LoopMode::Loop, d->M))
    return Status::error("field \"keys\": the spline through the keys could not be solved (key times too close?)");
  track.d_ = d;
  return {};
}

double KeyframeTrack::startTime() const { return d_->tFirst; }
double KeyframeTrack::endTime() const { return d_->tLast; }
double KeyframeTrack::period() const { return d_->period; }
LoopMode KeyframeTrack::mode() const { return d_->mode; }

KinematicState KeyframeTrack::evaluate(double t) const {
  const Data& d = *d_;
  const std::vector<double>& s = d.s;
  const int m = static_cast<int>(s.size()) - 1;
  double tau = d.speed * t;  // clip time
  auto hold = [&](int j) {
    KinematicState st;
    st.x = d.Y.row(j).head<3>().transpose();
    st.q = d.q0 * expRv(Eigen::Vector3d(d.Y.row(j).tail<3>().transpose()));
    return st;
  };
  if (d.constant) return hold(0);
  if (d.mode == LoopMode::Clamp) {
    if (tau <= s.front()) return hold(0);
    if (tau >= s.back()) return hold(m);
  } else {
    tau = s.front() + std::fmod(tau - s.front(), d.period);
    if (tau < s.front()) tau += d.period;
    if (tau >= s.back()) tau = s.front();
  }
  // Segment j with s_j <= tau < s_j+1.
  int j = static_cast<int>(std::upper_bound(s.begin(), s.end(), tau) - s.begin()) - 1;
  j = std::clamp(j, 0, m - 1);
  const double h = s[j + 1] - s[j];
  const double A = (s[j + 1] - tau) / h, B = (tau - s[j]) / h;
  const auto yj = d.Y.row(j), yk = d.Y.row(j + 1), Mj = d.M.row(j), Mk = d.M.row(j + 1);
  const Eigen::Matrix<double, 1, 6> y0 =
      A * yj + B * yk + ((A * A * A - A) * Mj + (B * B * B - B) * Mk) * (h * h / 6.0);
  const Eigen::Matrix<double, 1, 6> y1 =
      (yk - yj) / h + (-(3.0 * A * A - 1.0) * Mj + (3.0 * B * B - 1.0) * Mk) * (h / 6.0);
  const Eigen::Matrix<double, 1, 6> y2 = A * Mj + B * Mk;
  // d/dt = speed d/dtau
  const double k1 = d.speed, k2 = d.speed * d.speed;
  KinematicState st;
  st.x = y0.head<3>().transpose();
  st.v = k1 * y1.head<3>().transpose();
  st.a = k2 * y2.head<3>().transpose();
  const QuatJet e =
      expRotationVector(y0.tail<3>().transpose(), k1 * y1.tail<3>().transpose(), k2 * y2.tail<3>().transpose());
  // q = q0 e(t): q0 is constant, so q' = q0 e', q'' = q0 e''.
  const QuatJet q{d.q0 * e.q, d.q0 * e.dq, d.q0 * e.ddq};
  st.q = q.q;
  st.w = angularVelocity(q);
  st.alpha = angularAcceleration(q);
  return st;
}

KinematicMotion makeMotion(const KeyframeTrack& track) {
  return [track](double t) { return track.evaluate(t); };
}

Status makeMotion(const std::vector<Keyframe>& keys, const TrackOptions& options, KinematicMotion& motion) {
  KeyframeTrack track;
  if (Status s = KeyframeTrack::fromKeyframes(keys, options, track); !s.ok()) return s;
  motion = makeMotion(track);
  return {};
}

}  // namespace ponyhop

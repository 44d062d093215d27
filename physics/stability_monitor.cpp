#include "physics/stability_monitor.h"

#include <array>
#include <cmath>
#include <numbers>

#include "physics/rigid_body.h"

namespace ponyhop {

namespace {

// atan(k / 64) for k = 0 ... 64, each std::atan's (within an ulp).
const std::array<double, 65> kAtanTable = [] {
  std::array<double, 65> t{};
  for (int k = 0; k <= 64; ++k) t[size_t(k)] = std::atan(k / 64.0);
  return t;
}();

}  // namespace

// t = y / x (or x / y beyond 1, atan2 = pi / 2 - atan(x / y)) is split as t = c + (t - c) with
// c = k / 64 the nearest grid point: atan t = atan c + atan u, u = (t - c) / (1 + t c), |u| <=
// 1/128, where four terms of atan's series u (1 - u^2 / 3 + u^4 / 5 - u^6 / 7) leave out
// u^9 / 9 < 2e-18 u. Two divisions and eight multiply-adds instead of libm's general atan2 (7 % of
// a tree step at N = 8 and dt = 1/80 s, where most bodies turn beyond the monitor's series).
double atan2NonNegative(double y, double x) {
  const bool swap = y > x;
  const double t = swap ? x / y : y / x;
  if (!(t >= 0.0 && t <= 1.0)) return std::atan2(y, x);  // NaN, or both zero
  const int k = static_cast<int>(t * 64.0 + 0.5);
  const double c = k * (1.0 / 64.0);
  const double u = (t - c) / (1.0 + t * c);
  const double u2 = u * u;
  constexpr double k3 = 1.0 / 3.0, k5 = 1.0 / 5.0, k7 = 1.0 / 7.0;
  const double a = kAtanTable[size_t(k)] + u * (1.0 - u2 * (k3 - u2 * (k5 - u2 * k7)));
  return swap ? 0.5 * std::numbers::pi - a : a;
}

namespace {
// |phi|^2 for the turn from q0 to q1 (unit quaternions): phi = 2 atan2(|v|, |w|) of q1 q0^-1 (the
// shortest rotation; atan2 does not need the product normalized). A step's turn is small: then
// atan(t) = t (1 - t^2 / 3 + t^4 / 5), whose error t^7 / 7 is below 1.5e-13 t for t < 0.01.
// Always inlined into the monitor's pass over the bodies (GCC left it a call per body).
[[gnu::always_inline]] inline double turnSquared(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q0) {
  const Eigen::Quaterniond dq = q1 * q0.conjugate();
  const double s2 = dq.vec().squaredNorm(), c = std::abs(dq.w());
  if (s2 < 1e-4 * c * c) {  // s < 0.01 c: angle = 2 t (1 - t^2 / 3 + t^4 / 5), t = s / c, squared without a sqrt
    const double t2 = s2 / (c * c);
    const double series = 1.0 - t2 * (1.0 / 3.0 - 0.2 * t2);
    return 4.0 * t2 * series * series;
  }
  const double angle = 2.0 * atan2NonNegative(std::sqrt(s2), c);
  return angle * angle;
}
}  // namespace

template <class Y, class A, class Alpha>
bool StabilityMonitor::observeWith(double h, size_t n, const Y& y, const A& a, const Alpha& alpha, double limit) {
  if (!has_previous_ || n != y_.size()) {
    y_.resize(n);
    f_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      y_[i] = y(i);
      f_[i].a = a(i);
      f_[i].alpha = alpha(i);
    }
    has_previous_ = true;
    increment_ = 0.0;
    strikes_ = 0;
    return false;
  }
  // One pass: each entry's differences, then the entry kept for the next step.
  double dy2 = 0.0, df2 = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const BodyState& yi = y(i);
    const Eigen::Vector3d& ai = a(i);
    const Eigen::Vector3d& alphai = alpha(i);
    BodyState& yp = y_[i];
    BodyAcceleration& fp = f_[i];
    dy2 += (yi.x - yp.x).squaredNorm() + turnSquared(yi.q, yp.q) + (yi.v - yp.v).squaredNorm() +
           (yi.w - yp.w).squaredNorm();
    df2 += (yi.v - yp.v).squaredNorm() + (yi.w - yp.w).squaredNorm() + (ai - fp.a).squaredNorm() +
           (alphai - fp.alpha).squaredNorm();
    yp = yi;
    fp.a = ai;
    fp.alpha = alphai;
  }
  const double increment = std::sqrt(dy2);
  h_rho_ = increment > 0.0 ? h * std::sqrt(df2) / increment : 0.0;
  growth_ = increment_ > 0.0 ? increment / increment_ : 0.0;
  const bool unstable = h_rho_ > limit && growth_ > kGrowth;
  strikes_ = unstable ? strikes_ + 1 : 0;
  increment_ = increment;
  return strikes_ >= 2;
}

bool StabilityMonitor::observe(double h, const State& y, const Accelerations& f, double limit) {
  return observeWith(
      h, y.size(), [&](size_t i) -> const BodyState& { return y[i]; },
      [&](size_t i) -> const Eigen::Vector3d& { return f[i].a; },
      [&](size_t i) -> const Eigen::Vector3d& { return f[i].alpha; }, limit);
}

bool StabilityMonitor::observe(double h, const std::vector<RigidBody>& bodies, const std::vector<int>& which,
                               double limit) {
  return observeWith(
      h, which.size(), [&](size_t i) -> const BodyState& { return bodies[which[i]].state(); },
      [&](size_t i) -> const Eigen::Vector3d& { return bodies[which[i]].a; },
      [&](size_t i) -> const Eigen::Vector3d& { return bodies[which[i]].alpha; }, limit);
}

}  // namespace ponyhop

#include "physics/stability_monitor.h"

#include <cmath>

#include "physics/rigid_body.h"

namespace ponyhop {

bool StabilityMonitor::observe(double h, const State& y, const Accelerations& f, double limit) {
  if (!has_previous_ || y.size() != y_.size()) {
    y_ = y;
    f_ = f;
    has_previous_ = true;
    increment_ = 0.0;
    strikes_ = 0;
    return false;
  }
  double dy2 = 0.0, df2 = 0.0;
  for (size_t i = 0; i < y.size(); ++i) {
    dy2 += (y[i].x - y_[i].x).squaredNorm() + rotationVector(y[i].q * y_[i].q.conjugate()).squaredNorm() +
           (y[i].v - y_[i].v).squaredNorm() + (y[i].w - y_[i].w).squaredNorm();
    df2 += (y[i].v - y_[i].v).squaredNorm() + (y[i].w - y_[i].w).squaredNorm() + (f[i].a - f_[i].a).squaredNorm() +
           (f[i].alpha - f_[i].alpha).squaredNorm();
  }
  const double increment = std::sqrt(dy2);
  h_rho_ = increment > 0.0 ? h * std::sqrt(df2) / increment : 0.0;
  growth_ = increment_ > 0.0 ? increment / increment_ : 0.0;
  const bool unstable = h_rho_ > limit && growth_ > kGrowth;
  strikes_ = unstable ? strikes_ + 1 : 0;
  increment_ = increment;
  y_ = y;
  f_ = f;
  return strikes_ >= 2;
}

}  // namespace ponyhop

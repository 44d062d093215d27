#include "physics/pgs.h"

#include <algorithm>
#include <cmath>

namespace ponyhop {

namespace {
constexpr int kMaxSweeps = 5000;  // sweeps at most
}  // namespace

int projectedGaussSeidel(const Eigen::MatrixXd& d, const Eigen::VectorXd& u0, const Eigen::VectorXd& target,
                         const std::vector<std::pair<int, int>>& blocks, const std::vector<double>& mu,
                         Eigen::VectorXd& p) {
  const int m = static_cast<int>(u0.size());
  p = Eigen::VectorXd::Zero(m);
  Eigen::VectorXd u = u0;
  double scale = 1e-300;
  for (int i = 0; i < m; ++i) scale = std::max(scale, std::abs(u0(i) - target(i)) / std::max(d(i, i), 1e-300));
  const auto update = [&](int i, double value) {
    const double delta = value - p(i);
    if (delta == 0.0) return 0.0;
    p(i) = value;
    u += d.col(i) * delta;
    return std::abs(delta);
  };
  int sweep = 0;
  for (; sweep < kMaxSweeps; ++sweep) {
    double change = 0.0;
    for (size_t c = 0; c < blocks.size(); ++c) {
      const int n = blocks[c].first;
      if (d(n, n) > 1e-300) change = std::max(change, update(n, std::max(0.0, p(n) + (target(n) - u(n)) / d(n, n))));
      if (blocks[c].second == 3) {
        for (int t = n + 1; t <= n + 2; ++t)
          if (d(t, t) > 1e-300) update(t, p(t) - u(t) / d(t, t));
        const double limit = mu[c] * p(n);
        const double len = std::hypot(p(n + 1), p(n + 2));
        if (len > limit) {
          const double s = len > 0.0 ? limit / len : 0.0;
          const double p1 = p(n + 1) * s, p2 = p(n + 2) * s;
          change = std::max(change, update(n + 1, p1));
          change = std::max(change, update(n + 2, p2));
        }
        // The tangents' change counts too (sticking).
      }
    }
    double tangent_residual = 0.0;
    for (size_t c = 0; c < blocks.size(); ++c) {
      if (blocks[c].second != 3) continue;
      const int n = blocks[c].first;
      const bool inside = std::hypot(p(n + 1), p(n + 2)) < mu[c] * p(n) * (1.0 - 1e-12);
      if (inside)
        tangent_residual =
            std::max(tangent_residual, std::hypot(u(n + 1), u(n + 2)) / std::max(d(n + 1, n + 1), 1e-300));
    }
    if (change <= 1e-13 * scale && tangent_residual <= 1e-12 * scale) break;
  }
  return sweep + 1;
}

}  // namespace ponyhop

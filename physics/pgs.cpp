#include "physics/pgs.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

namespace ponyhop {

namespace {

// One contact's impulse (normal, two tangents) with the others' fixed: b the velocities of its
// rows without its own impulse, minus the normal's target; A its 3 x 3 block of D. A sliding
// direction is found to `precision` (rad), first near the direction of `last` (the contact's
// impulse at the sweep before). Returns false when no case fits (degenerate blocks): the caller
// keeps the row-wise update.
// `ldlt`: A's factorization, made by the first call that needs it and kept for the next sweeps
// (A does not change within a solve).
bool solveContact(const Eigen::Matrix3d& a, const Eigen::Vector3d& b, double mu, double precision,
                  const Eigen::Vector3d& last, Eigen::Vector3d& p,
                  std::optional<Eigen::LDLT<Eigen::Matrix3d>>& cached) {
  if (b(0) >= 0.0) {  // separating without an impulse
    p.setZero();
    return true;
  }
  Eigen::Vector3d stick = Eigen::Vector3d::Zero();
  if (!cached) cached.emplace(a);
  const Eigen::LDLT<Eigen::Matrix3d>& ldlt = *cached;
  if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
    stick = ldlt.solve(-b);
    if (stick(0) >= 0.0 && stick.tail<2>().norm() <= mu * stick(0)) {
      p = stick;
      return true;
    }
  }
  // Sliding along d = (cos t, sin t): p_t = -mu p_n d; the normal row at its target gives
  // p_n = -b_n / (A_nn - mu A_nt d), the slip u_t = b_t + p_n (A_tn - mu A_tt d) must be +d: the
  // cross product of d and u_t vanishes with d . u_t >= 0. The directions are unit vectors, not
  // angles: the scan's come from a table and a bisection's midpoint is the normalized sum of its
  // ends (the direction at the mean angle), so no sine or cosine is taken in a sweep.
  const auto slip = [&](const Eigen::Vector2d& d, double& pn, Eigen::Vector2d& ut) {
    const double den = a(0, 0) - mu * a.block<1, 2>(0, 1).dot(d);
    if (!(den > 0.0)) {
      ut.setZero();  // no sliding impulse along d (its g is 0 and it is no bracket end)
      return false;
    }
    pn = -b(0) / den;
    ut = b.tail<2>() + pn * (a.block<2, 1>(1, 0) - mu * a.block<2, 2>(1, 1) * d);
    return ut.dot(d) >= 0.0;
  };
  const auto cross = [](const Eigen::Vector2d& d, const Eigen::Vector2d& ut) {
    return d.x() * ut.y() - d.y() * ut.x();
  };
  // Near the last direction first. From one sweep to the next a sliding contact's direction
  // moves by about the change of the others' impulses, so the root of g = d x u_t is bracketed
  // within a few steps of the guess and closed in by regula falsi (Illinois: the end that stays
  // has its g halved, so both ends converge): about ten evaluations where the scan and its
  // bisection below take about fifty. The directions ahead of the guess e are parametrized
  // without sines, d(s) = (e + s e') / sqrt(1 + s^2) with e' = e turned by 90 deg (s = tan of the
  // angle from e, which it bounds from above: the bracket's width in s bounds it in angle), and
  // the steps are s = +-1e-4 4^k up to 7e3 (90 deg less 0.01). With no last impulse the guess is
  // opposite the sticking impulse's tangents (what friction would need to stop the slip). A
  // bracket needs both ends valid (d . u_t >= 0), as in the scan; when none is found within a
  // quarter turn either way the scan decides.
  const auto local = [&](const Eigen::Vector2d& e) {
    const Eigen::Vector2d e1(-e.y(), e.x());
    const auto along = [&e, &e1](double s) { return Eigen::Vector2d((e + s * e1) / std::sqrt(1.0 + s * s)); };
    double pn = 0.0;
    Eigen::Vector2d ut;
    const bool ok0 = slip(e, pn, ut);
    const double g0 = cross(e, ut);
    double sa = 0.0, ga = g0, sb = 0.0, gb = g0;
    bool found = ok0 && g0 == 0.0;
    double side_s[2] = {0.0, 0.0}, side_g[2] = {g0, g0};
    bool side_ok[2] = {ok0, ok0};
    for (double step = 1e-4; !found && step < 2e4; step *= 4.0) {
      for (int k = 0; k < 2 && !found; ++k) {
        const double s = k == 0 ? step : -step;
        const Eigen::Vector2d d = along(s);
        const bool ok = slip(d, pn, ut);
        const double g = cross(d, ut);
        if (ok && side_ok[k] && (g == 0.0 || (g > 0.0) != (side_g[k] > 0.0))) {
          sa = side_s[k];
          ga = side_g[k];
          sb = s;
          gb = g;
          found = true;
        }
        side_s[k] = s;
        side_g[k] = g;
        side_ok[k] = ok;
      }
    }
    if (!found) return false;
    int kept = 0;  // the end the last step kept: 1 a, -1 b
    for (int it = 0; it < 100 && gb != 0.0 && std::abs(sb - sa) > precision; ++it) {
      double s = (sa * gb - sb * ga) / (gb - ga);
      if (!(s > std::min(sa, sb) && s < std::max(sa, sb))) s = 0.5 * (sa + sb);
      const Eigen::Vector2d d = along(s);
      slip(d, pn, ut);
      const double g = cross(d, ut);
      if (g == 0.0) {
        sa = sb = s;
        break;
      }
      if ((g > 0.0) == (ga > 0.0)) {
        sa = s;
        ga = g;
        if (kept == -1) gb *= 0.5;
        kept = -1;
      } else {
        sb = s;
        gb = g;
        if (kept == 1) ga *= 0.5;
        kept = 1;
      }
    }
    const Eigen::Vector2d end = along(gb == 0.0 ? sb : 0.5 * (sa + sb));
    if (!slip(end, pn, ut) || !(pn >= 0.0)) return false;
    p << pn, -mu * pn * end;
    return true;
  };
  const Eigen::Vector2d guess =
      last.tail<2>().squaredNorm() > 0.0 ? Eigen::Vector2d(-last.tail<2>()) : Eigen::Vector2d(-stick.tail<2>());
  if (guess.squaredNorm() > 0.0 && local(guess.normalized())) return true;
  constexpr int kAngles = 32;
  static const std::array<Eigen::Vector2d, kAngles + 1> kScan = [] {
    std::array<Eigen::Vector2d, kAngles + 1> dirs;
    for (int k = 0; k <= kAngles; ++k)
      dirs[k] = {std::cos(2.0 * M_PI * k / kAngles), std::sin(2.0 * M_PI * k / kAngles)};
    return dirs;
  }();
  double pn = 0.0;
  Eigen::Vector2d ut;
  Eigen::Vector2d lo = kScan[0];
  double glo = 0.0;
  bool has_lo = false;
  for (int k = 0; k <= kAngles; ++k) {
    const Eigen::Vector2d& t = kScan[k];
    const bool ok = slip(t, pn, ut);
    const double g = cross(t, ut);
    if (ok && has_lo && (g == 0.0 || (g > 0.0) != (glo > 0.0))) {
      Eigen::Vector2d hi = t;
      for (int it = 0; it < 60 && (hi - lo).squaredNorm() > precision * precision; ++it) {
        const Eigen::Vector2d mid = (lo + hi).normalized();
        slip(mid, pn, ut);
        if ((cross(mid, ut) > 0.0) == (glo > 0.0))
          lo = mid;
        else
          hi = mid;
      }
      const Eigen::Vector2d end = (lo + hi).normalized();
      if (slip(end, pn, ut) && pn >= 0.0) {
        p << pn, -mu * pn * end;
        return true;
      }
    }
    has_lo = ok;
    lo = t;
    glo = g;
  }
  // No sliding direction found: the slip is within round-off of zero (the contact is on the
  // border of sticking, where ut . d changes sign with the noise). The sticking impulse with its
  // tangents scaled onto the rim is the answer there.
  if (ldlt.info() != Eigen::Success || !(stick(0) > 0.0)) return false;
  const double len = stick.tail<2>().norm();
  p = stick;
  if (len > 0.0) p.tail<2>() *= mu * stick(0) / len;
  return true;
}

}  // namespace

PgsResult projectedGaussSeidel(const Eigen::MatrixXd& d, const Eigen::VectorXd& u0, const Eigen::VectorXd& target,
                               const std::vector<std::pair<int, int>>& blocks, const std::vector<double>& mu,
                               Eigen::VectorXd& p, const PgsSettings& settings) {
  const int m = static_cast<int>(u0.size());
  Eigen::VectorXd u = u0;
  if (settings.warm_start && p.size() == m && p.squaredNorm() > 0.0) {
    // The problem's energy along the ray a p: E(a) = a p.(u0 - target) + a^2 p.D p / 2, least at
    // a* = -p.(u0 - target) / p.D p; a in [0, 1] keeps E(a p) <= E(0) = 0 (a feasible start: the
    // cone is a cone).
    const double pdp = p.dot(d * p), slope = p.dot(u0 - target);
    const double a = pdp > 0.0 && slope < 0.0 ? std::min(1.0, -slope / pdp) : 0.0;
    p *= a;
    if (a > 0.0) u.noalias() += d * p;
  } else {
    p = Eigen::VectorXd::Zero(m);
  }
  double scale = 1e-300;
  for (int i = 0; i < m; ++i) scale = std::max(scale, std::abs(u0(i) - target(i)) / std::max(d(i, i), 1e-300));
  const auto update = [&](int i, double value) {
    const double delta = value - p(i);
    if (delta == 0.0) return 0.0;
    p(i) = value;
    u += d.col(i) * delta;
    return std::abs(delta);
  };
  // A sliding direction off by e moves the friction impulse by about e of it: a hundredth of the
  // tolerance is below what the sweeps resolve (1e-15 rad at the analytic shapes' 1e-13, 1e-6
  // against a grid, where the bisection took 48 steps where 18 do).
  const double direction_precision = 1e-2 * settings.tolerance;
  // The slip a sticking contact may keep, squared (compared with |u_t|^2 / D_tt^2).
  const double slip2 = (10.0 * settings.tolerance * scale) * (10.0 * settings.tolerance * scale);
  PgsResult result;
  std::vector<std::optional<Eigen::LDLT<Eigen::Matrix3d>>> factored(blocks.size());
  int sweep = 0;
  for (; sweep < settings.max_sweeps; ++sweep) {
    double change = 0.0;
    for (size_t c = 0; c < blocks.size(); ++c) {
      const int n = blocks[c].first;
      if (settings.exact_blocks && blocks[c].second == 3) {
        const Eigen::Matrix3d a = d.block<3, 3>(n, n);
        const Eigen::Vector3d own = p.segment<3>(n);
        Eigen::Vector3d b = u.segment<3>(n) - a * own;
        b(0) -= target(n);
        Eigen::Vector3d solved;
        if (solveContact(a, b, mu[c], direction_precision, own, solved, factored[c])) {
          for (int k = 0; k < 3; ++k) change = std::max(change, update(n + k, solved(k)));
          continue;
        }
      }
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
    if (change > settings.tolerance * scale) continue;
    // Sticking contacts (strictly inside the disc) must not slip: squared norms, no hypot (this
    // check runs every sweep).
    bool slipping = false;
    for (size_t c = 0; c < blocks.size() && !slipping; ++c) {
      if (blocks[c].second != 3) continue;
      const int n = blocks[c].first;
      const double rim = mu[c] * p(n) * (1.0 - 1e-12);
      const bool inside = p(n + 1) * p(n + 1) + p(n + 2) * p(n + 2) < rim * rim && rim > 0.0;
      const double dt = std::max(d(n + 1, n + 1), 1e-300);
      if (inside && (u(n + 1) * u(n + 1) + u(n + 2) * u(n + 2)) / (dt * dt) > slip2) slipping = true;
    }
    if (!slipping) break;
  }
  result.sweeps = std::min(sweep + 1, settings.max_sweeps);
  result.capped = sweep == settings.max_sweeps;
  return result;
}

}  // namespace ponyhop

#include "physics/models/guide.h"

#include <algorithm>
#include <map>

#include "physics/constraint.h"
#include "physics/world.h"

namespace ponyhop {

Status validate(const GuideParams& p, int links, const std::string& prefix) {
  std::map<int, std::vector<double>> times;
  for (size_t i = 0; i < p.knots.size(); ++i) {
    const GuideKnot& k = p.knots[i];
    if (k.joint >= links) {
      return Status::error(prefix + ".knots." + std::to_string(i) + ".joint: " + std::to_string(k.joint) +
                           " is not a joint of the chain (0.." + std::to_string(links - 1) + ")");
    }
    times[k.joint].push_back(k.t);
  }
  for (auto& [joint, ts] : times) {
    std::sort(ts.begin(), ts.end());
    if (ts.size() < 2) {
      return Status::error(prefix + ".knots: joint " + std::to_string(joint) +
                           " has one knot; a joint's curve needs at least two (or none)");
    }
    for (size_t i = 1; i < ts.size(); ++i) {
      if (ts[i] == ts[i - 1]) {
        return Status::error(prefix + ".knots: joint " + std::to_string(joint) +
                             " has two knots at t = " + std::to_string(ts[i]) + " s");
      }
    }
  }
  return {};
}

int guideWeights(const std::vector<double>& times, double t, std::array<double, 4>& w) {
  w.fill(0.0);
  const size_t n = times.size();
  if (n < 2 || t < times.front() || t > times.back()) return -1;
  // Interval i = [t_i, t_{i+1}] holding t; the last knot belongs to the last interval.
  const size_t i = std::min<size_t>(size_t(std::upper_bound(times.begin(), times.end(), t) - times.begin()), n - 1) - 1;
  const double h = times[i + 1] - times[i];
  const double s = (t - times[i]) / h;
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  // Tangents m_i = (tau_{i+1} - tau_{i-1}) / (t_{i+1} - t_{i-1}), one-sided at the ends: index
  // i - 1 clipped to i at the first knot, i + 2 clipped to i + 1 at the last. w[0..3] weigh
  // knots i - 1 .. i + 2.
  const bool first = i == 0, last = i + 2 >= n;
  const double a0 = 1.0 / (times[i + 1] - times[first ? i : i - 1]);
  const double a1 = 1.0 / (times[last ? i + 1 : i + 2] - times[i]);
  w[1] += h00;
  w[2] += h01;
  w[2] += h10 * h * a0;
  w[first ? 1 : 0] -= h10 * h * a0;
  w[last ? 2 : 3] += h11 * h * a1;
  w[1] -= h11 * h * a1;
  return int(i);
}

void GuideTorques::set(const GuideParams& p) {
  times_.assign(links_.size(), {});
  torques_.assign(links_.size(), {});
  std::vector<std::vector<std::pair<double, Eigen::Vector3d>>> sorted(links_.size());
  for (const GuideKnot& k : p.knots) {
    if (k.joint >= 0 && size_t(k.joint) < links_.size()) sorted[size_t(k.joint)].emplace_back(k.t, k.torque);
  }
  for (size_t j = 0; j < sorted.size(); ++j) {
    std::sort(sorted[j].begin(), sorted[j].end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [t, tau] : sorted[j]) {
      times_[j].push_back(t);
      torques_[j].push_back(tau);
    }
  }
}

Eigen::Vector3d GuideTorques::torque(size_t joint, double t) const {
  Eigen::Vector3d tau = Eigen::Vector3d::Zero();
  if (joint >= times_.size()) return tau;
  std::array<double, 4> w;
  const int interval = guideWeights(times_[joint], t, w);
  if (interval < 0) return tau;
  const int n = int(times_[joint].size());
  for (int k = 0; k < 4; ++k) {
    const int i = interval - 1 + k;
    if (w[size_t(k)] != 0.0 && i >= 0 && i < n) tau += w[size_t(k)] * torques_[joint][size_t(i)];
  }
  return tau;
}

void GuideTorques::applyForces(World& world, double t) {
  std::vector<RigidBody>& bodies = world.bodies();
  for (size_t j = 0; j < links_.size(); ++j) {
    if (times_[j].empty()) continue;
    const Eigen::Vector3d tau = torque(j, t);
    bodies[size_t(links_[j])].torque += tau;
    if (dynamicBody(bodies, parents_[j])) bodies[size_t(parents_[j])].torque -= tau;
  }
}

}  // namespace ponyhop

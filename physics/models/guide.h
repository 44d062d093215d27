// The guide: a smooth torque per joint of a chain over time, the control that the goal solve
// (sim/goal_solve.h, docs/GOALS.md) finds and the scene keeps (`guide` section) so that every
// replay (sim, render, export) gives the same motion.
//
// Joint j's torque tau_j(t) (world frame, N m) acts on link j and, reversed, on the body it hangs
// from (link j - 1, or the chain's parent when that is dynamic): an internal pair like the bending
// spring's, a muscle at the joint, so it never pushes the chain as a whole. tau_j is the cubic
// Hermite curve through the joint's knots (t_i, tau_i) with Catmull-Rom tangents
//   m_i = (tau_{i+1} - tau_{i-1}) / (t_{i+1} - t_{i-1}),  one-sided at the two ends,
// and zero before the first knot and after the last. It is linear in the knot torques: with the
// knot times fixed, tau_j(t) = sum_i B_i(t) tau_i, at most four B_i non-zero at any t.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "physics/controller.h"
#include "physics/models/hopper_params.h"
#include "physics/reflect.h"
#include "physics/status.h"

namespace ponyhop {

struct GuideKnot {
  int joint = 0;                                     // 0: the root joint
  double t = 0.0;                                    // s
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  // N m, world frame, on link `joint`

  template <class V>
  void reflect(V& v) {
    v("joint", joint, {.min = 0, .max = 4095, .help = "Joint (0: the root; joint j turns link j against its parent)"});
    v("t", t, {.unit = "s", .min = 0, .max = 1e6, .help = "Time of the knot"});
    v("torque", torque, {.unit = "N m", .min = -1e3, .max = 1e3, .help = "Torque at the knot (world frame)"});
  }
};

struct GuideParams {
  bool enabled = true;  // false: the unguided motion (the knots are kept)
  std::vector<GuideKnot> knots;
  // The first hopper's solved commands (docs/GOALS.md, "The hopper"): a course like hopper.script,
  // each key from its t on, in force instead of hopper.script while the guide is enabled.
  std::vector<HopperCommandKey> script;

  template <class V>
  void reflect(V& v) {
    v("enabled", enabled, {.help = "Apply the solved torques (false: the unguided motion)", .apply = Apply::Restart});
    v("knots", knots,
      {.help = "Torque knots per joint (a smooth curve through each joint's knots, zero outside them)",
       .apply = Apply::Restart});
    v("script", script,
      {.help = "The first hopper's solved commands, each key from its t on (replaces hopper.script while enabled)",
       .apply = Apply::Restart});
  }
};

// The first invalid knot list for a chain of `links` links (a joint out of range, a joint with one
// knot, two knots of a joint at the same time), or ok.
Status validate(const GuideParams& p, int links, const std::string& prefix = "guide");

// The curve's weights at t for knot times `times` (increasing): the interval i holding t is
// returned and tau(t) = sum_k w[k] tau_{i - 1 + k}, k = 0..3 (a weight whose knot index falls
// outside the list is zero); -1 and all weights zero outside [times.front(), times.back()].
int guideWeights(const std::vector<double>& times, double t, std::array<double, 4>& w);

// The controller: per joint its knots, applied at every force evaluation.
class GuideTorques final : public Controller {
 public:
  // links[j]: the body joint j turns; parents[j]: the body it hangs from (kWorldBody or kinematic:
  // no reaction is applied there).
  GuideTorques(std::vector<int> links, std::vector<int> parents)
      : links_(std::move(links)), parents_(std::move(parents)) {}
  // Replaces the knots (validated by the caller).
  void set(const GuideParams& p);
  void applyForces(World& world, double t) override;
  bool dependsOnVelocity() const override { return false; }  // time only
  // Joint j's torque at t (zero for a joint without knots).
  Eigen::Vector3d torque(size_t joint, double t) const;
  size_t joints() const { return links_.size(); }

 private:
  std::vector<int> links_, parents_;
  std::vector<std::vector<double>> times_;  // per joint, increasing
  std::vector<std::vector<Eigen::Vector3d>> torques_;
};

}  // namespace ponyhop

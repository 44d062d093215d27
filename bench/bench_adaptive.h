// `ponyhop bench --adaptive-only`: adaptive dynamics (physics.adaptive_joints,
// physics.adaptive_tolerance; docs/SOLVERS.md) against the full featherstone step on long chains,
// at the same dt: the tip's error (against that full run and against a converged one), the energy
// drift, the CPU cost per simulated second and the joints that moved. Its table goes to OUT/adaptive.md
// (docs/bench/adaptive.md).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace ponyhop {

struct AdaptiveBenchOptions {
  std::vector<int> links{64, 256, 1024};
  std::vector<std::string> anchors{"fixed", "shake"};
  std::vector<int> budgets{4, 8, 16, 32, 64};        // budgets at or above N are left out (the full run)
  std::vector<double> tolerances{1e-9, 1e-7, 1e-5};  // J, the threshold form
  double seconds = 2.0;                              // simulated per run
  int dt_denominator = 960;                          // dt = 1 / this
  int repeats = 2;                                   // timed runs per variant, interleaved; the least kept
  // The converged reference: the full step with max_step_rotation this small (deg), not timed; its
  // distance from the full run at the bench's own settings is that run's own time-step error.
  // 0: no reference (its columns say "-").
  double reference_rotation = 0.5;
  // Diagnostic rows (docs/bench/adaptive.md, "Oracles"), each at every budget k of `budgets`:
  //   acc       each step, the k joints of largest |u'| in the full model's ABA at the current state;
  //   ref-speed each step, the k joints of largest |u| in the full run at the same time;
  //   ref-fit   each step, the k stretches that fit the full run's link angular velocities best
  //             (least squares, a dynamic programme over the chain);
  //   even      the even split, fixed from the first step (the shipped choice through the chooser);
  //   graded-P  a fixed set, joint j of k at depth n (1 - (1 - j / k)^P): P > 1 denser at the tip;
  //   chain     no adaptivity: the full step on a chain of k links (same length and mass).
  std::vector<std::string> oracles;
  std::string out = "docs/bench";
  std::string command_line;
};

// ref-fit's choice: the starts (depths, the first 0) of the k stretches of a chain whose links'
// angular velocities w (in depth order) are best fitted by one angular velocity per stretch, in
// least squares (sum over each stretch of |w_j - its mean|^2); k is capped at w's size.
std::vector<int> bestRigidFit(const std::vector<Eigen::Vector3d>& w, int k);

// Small planar oscillations of a chain of `links` uniform thin rods (length L, mass M in all)
// hanging under gravity g about the vertical (docs/bench/adaptive.md, "A chain of k pieces is
// another pendulum"): M'' th + K th = 0 with th_i link i's angle from the vertical (i = 0 at the
// anchor), link l's centre at x_l = (L / n) (sum_{i<l} th_i + th_l / 2), so
// M = m (L/n)^2 (J^T J + 1/12), J_li = 1 for i < l, 1/2 for i = l, and K = diag(m g (L/n) (n - i - 1/2)).
// The first `modes` angular frequencies (rad/s), lowest first.
std::vector<double> hangingChainFrequencies(int links, int modes, double length = 1.0, double g = 9.81);
// The continuum's (the hanging chain of Bernoulli and Euler): (j_{0,m} / 2) sqrt(g / L), j_{0,m}
// the zeros of the Bessel function J0, for m = 1 to 12.
std::vector<double> continuumChainFrequencies(double length = 1.0, double g = 9.81);

// Runs the section and writes OUT/adaptive.md; 0 when every run finished.
int runAdaptiveBench(const AdaptiveBenchOptions& options);

}  // namespace ponyhop

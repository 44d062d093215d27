// `ponyhop bench --adaptive-only` (bench/bench_adaptive.cpp) with its diagnostic oracles
// (docs/bench/adaptive.md, "Oracles"): ref-fit's least-squares partition, and a short run that
// writes a row per oracle with no more active joints than the budget, and refuses an unknown one.
#include "bench/bench_adaptive.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/out_util.h"

namespace ponyhop {
namespace {

// Three plateaus of angular velocity (with a small ripple) along 12 links: three stretches fit
// them exactly where they change; two stretches merge the two closest plateaus.
TEST(BenchAdaptive, RigidFitFindsTheStretchesOfEqualAngularVelocity) {
  std::vector<Eigen::Vector3d> w;
  for (int j = 0; j < 12; ++j) {
    const double ripple = 1e-3 * ((j % 2) ? 1.0 : -1.0);
    const Eigen::Vector3d plateau = j < 3   ? Eigen::Vector3d(0, 1, 0)
                                    : j < 8 ? Eigen::Vector3d(0, 4, 1)
                                            : Eigen::Vector3d(0, 4.5, 1);
    w.push_back(plateau + Eigen::Vector3d(ripple, 0, 0));
  }
  EXPECT_EQ(bestRigidFit(w, 3), (std::vector<int>{0, 3, 8}));
  EXPECT_EQ(bestRigidFit(w, 2), (std::vector<int>{0, 3}));
  EXPECT_EQ(bestRigidFit(w, 1), (std::vector<int>{0}));
  EXPECT_EQ(bestRigidFit(w, 40).size(), 12u);  // capped at one stretch per link
}

// The linear modes of a hanging chain of thin rods tend to the continuum's (j0m / 2) sqrt(g / L):
// 512 rods within 0.15 % for the first 12 modes, about 4x closer than 256; 16 rods mistune the 5th mode by 6.3 % and
// the 12th by 42 % (docs/bench/adaptive.md, "A chain of k pieces is another pendulum"), 64 rods the 12th by 4.8 %: the
// error grows about as (m / n)^2.
TEST(BenchAdaptive, AChainOfRodsHasTheContinuumsModesWhenFine) {
  const std::vector<double> cont = continuumChainFrequencies();
  ASSERT_EQ(cont.size(), 12u);
  const std::vector<double> fine = hangingChainFrequencies(512, 12), half = hangingChainFrequencies(256, 12);
  ASSERT_EQ(fine.size(), 12u);
  for (size_t m = 0; m < 12; ++m) {
    EXPECT_NEAR(fine[m] / cont[m], 1.0, 1.5e-3) << "mode " << m + 1;
    EXPECT_LT(std::abs(fine[m] / cont[m] - 1.0), 0.3 * std::abs(half[m] / cont[m] - 1.0) + 1e-9) << "mode " << m + 1;
  }
  const std::vector<double> coarse = hangingChainFrequencies(16, 12), mid = hangingChainFrequencies(64, 12);
  EXPECT_NEAR(coarse[0] / cont[0], 1.0, 1e-3);
  EXPECT_NEAR(coarse[4] / cont[4] - 1.0, 0.063, 0.002);
  EXPECT_NEAR(coarse[11] / cont[11] - 1.0, 0.42, 0.01);
  EXPECT_NEAR(mid[11] / cont[11] - 1.0, 0.048, 0.002);
  EXPECT_EQ(hangingChainFrequencies(4, 12).size(), 4u);
}

// The cells of the row that starts with `head` (after it), or empty.
std::vector<std::string> adaptiveRow(const std::string& text, const std::string& head) {
  const size_t at = text.find(head);
  if (at == std::string::npos) return {};
  std::stringstream line(text.substr(at + head.size(), text.find('\n', at) - at - head.size()));
  std::vector<std::string> cells;
  for (std::string cell; std::getline(line, cell, '|');) cells.push_back(cell);
  return cells;
}

TEST(BenchAdaptive, EveryOracleWritesARowWithinTheBudget) {
  AdaptiveBenchOptions o;
  o.links = {24};
  o.anchors = {"fixed"};
  o.budgets = {4};
  o.tolerances = {};
  o.seconds = 0.1;
  o.repeats = 1;
  o.reference_rotation = 0.0;
  o.oracles = {"acc", "ref-speed", "ref-fit", "even", "graded-1.5", "chain"};
  o.out = std::string(PONYHOP_TEST_OUT) + "/bench-adaptive";
  o.command_line = "bench_adaptive_test";
  ASSERT_EQ(runAdaptiveBench(o), 0);
  const std::string s = testing::readFile(o.out + "/adaptive.md");
  const std::vector<std::string> full = adaptiveRow(s, "| 24 | fixed | full |");
  ASSERT_FALSE(full.empty()) << s;
  for (const std::string& oracle : o.oracles) {
    const std::vector<std::string> cells = adaptiveRow(s, "| 24 | fixed | " + oracle + " 4 |");
    ASSERT_GE(cells.size(), 12u) << oracle << "\n" << s;
    // Cells: RMS 0.5 s, 1 s, all, max, conv. x2, drift, CPU, full / this, active mean, active max, substeps.
    const double rms = std::strtod(cells[0].c_str(), nullptr), active_max = std::strtod(cells[10].c_str(), nullptr);
    EXPECT_GT(rms, 0.0) << oracle;  // a reduced model, not the full run
    EXPECT_LT(rms, 5.0) << oracle;  // % of the length, 0.1 s after the release
    EXPECT_LE(active_max, 4.0) << oracle;
    EXPECT_GE(active_max, 1.0) << oracle;
  }
  for (const char* bad : {"best", "graded-", "graded-0", "graded-2x"}) {
    o.oracles = {bad};
    try {
      runAdaptiveBench(o);
      ADD_FAILURE() << "an unknown oracle ran: " << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("--adaptive-oracles: unknown oracle \"" + std::string(bad) + "\" (allowed:"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace ponyhop

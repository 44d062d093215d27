// The report logic of `ponyhop bench` (bench_run.h, bench_report.h). The scaling sweep: the
// configurations run in interleaved rounds (ABBA), one that stops is recorded with its reason and
// not run again, ours against the fastest peer is taken round by round; our configurations swing
// the chain with their drift control; a peer's joint error is read from its links' ends. Cost at
// equal accuracy: per level the cheapest bounded run of ours and of each peer engine that reaches
// it, the lines where a peer is cheaper first, the same from the rows as from their bench.csv.
// No timing is asserted.
#include "bench/bench_report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_peers.h"
#include "bench/bench_run.h"

namespace ponyhop {
namespace {

// A chain that only counts: it records when it was made, stops after `stop_after` steps (0:
// never) and reports a joint error that grows by `drift` per step.
class FakeSubject final : public ScalingSubject {
 public:
  FakeSubject(long stop_after, double drift) : stop_after_(stop_after), drift_(drift) {}
  bool step() override {
    ++steps_;
    for (int k = 0; k < 100; ++k) sink_ = sink_ + k;  // a little work, so that a step takes CPU time
    return stop_after_ == 0 || steps_ < stop_after_;
  }
  bool ok() override { return stop_after_ == 0 || steps_ < stop_after_; }
  double jointError() override { return drift_ * steps_; }
  std::string why() const override { return "stopped on purpose"; }
  double time() const override { return steps_ * kBenchGrid; }

 private:
  long stop_after_ = 0;
  long steps_ = 0;
  double drift_ = 0.0;
  volatile double sink_ = 0.0;
};

ScalingConfig fake(const std::string& name, bool peer, std::vector<std::string>& made, long stop_after = 0,
                   double drift = 0.0) {
  ScalingConfig c;
  c.name = name;
  c.drift = peer ? "peer" : "test";
  c.peer = peer;
  c.make = [name, &made, stop_after, drift](int, std::string&) -> std::unique_ptr<ScalingSubject> {
    made.push_back(name);
    return std::make_unique<FakeSubject>(stop_after, drift);
  };
  return c;
}

// A run whose step does not divide the reference's stride is compared at the times both have:
// the tip at k / 100 s against the reference's sample at that time (every 5th of the run's lands
// on 1/1920 s), not at its rounded ratio (19: 19 k / 1920 s).
TEST(BenchError, ARunIsComparedWithTheReferenceAtItsOwnTimes) {
  const auto path = [](double t) { return Eigen::Vector3d(std::sin(3.0 * t), std::cos(2.0 * t), t * t); };
  Trajectory ref;
  ref.stride = kBenchGrid;
  for (int j = 0; j <= 1920; ++j) ref.p.push_back(path(j * kBenchGrid));
  for (int d : {100, 1000, 80, 1920, 7}) {
    Trajectory run;
    run.stride = 1.0 / d;
    for (int k = 0; k <= d; ++k) run.p.push_back(path(k * run.stride));
    const auto e = trajectoryError(run, ref, 1.0);
    EXPECT_LT(e[0], 1e-12) << "1/" << d;
    EXPECT_LT(e[1], 1e-12) << "1/" << d;
  }
  // Off the path: the error is seen (at the times both have).
  Trajectory off;
  off.stride = 0.01;
  for (int k = 0; k <= 100; ++k) off.p.push_back(path(k * off.stride) + Eigen::Vector3d(0.0, 0.0, 0.5));
  EXPECT_NEAR(trajectoryError(off, ref, 1.0)[0], 0.5, 1e-12);
}

TEST(BenchScaling, RoundsInterleaveAndAStoppedRunIsNotRepeated) {
  std::vector<std::string> made;
  const std::vector<ScalingConfig> configs = {fake("a", false, made, 0, 1e-6), fake("b", true, made),
                                              fake("c", false, made, 20, 1e-6)};
  const double seconds = 96 * kBenchGrid;  // 96 steps: 12 blocks of 1/240 s
  const auto rows = runScalingSweep(configs, 4, 4, seconds, 1e9);
  // Round 0 in order, round 1 reversed, ...; c stopped in round 0 and is not made again.
  EXPECT_EQ(made, (std::vector<std::string>{"a", "b", "c", "b", "a", "a", "b", "b", "a"}));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].status, "ok");
  EXPECT_EQ(rows[0].us_per_step.size(), 4u);
  EXPECT_EQ(rows[0].steps, 96);
  EXPECT_NEAR(rows[0].joint_error, 96e-6, 1e-12);  // the largest over the timed run
  EXPECT_EQ(rows[1].us_per_step.size(), 4u);
  EXPECT_EQ(rows[2].status, "failed");
  EXPECT_EQ(rows[2].reason, "stopped on purpose");
  EXPECT_TRUE(rows[2].us_per_step.empty());
  EXPECT_NEAR(rows[2].joint_error, 16e-6, 1e-12);  // up to its last whole block
}

TEST(BenchScaling, ARoundOverTheBudgetIsSkipped) {
  std::vector<std::string> made;
  const auto rows = runScalingSweep({fake("a", false, made)}, 4, 3, 1.0, 0.0);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].status, "skipped");
  EXPECT_NE(rows[0].reason.find("budget"), std::string::npos) << rows[0].reason;
  EXPECT_EQ(made.size(), 1u);
}

ScalingRow row(const std::string& config, bool peer, int links, std::vector<double> us, std::string status = "ok") {
  ScalingRow r;
  r.config = config;
  r.peer = peer;
  r.links = links;
  r.us_per_step = std::move(us);
  r.status = std::move(status);
  return r;
}

TEST(BenchScaling, OursAgainstTheFastestPeerRoundByRound) {
  const std::vector<ScalingRow> rows = {
      row("tree", false, 8, {1.0, 2.0, 3.0}),
      row("dense", false, 8, {}, "failed"),
      row("p/slow", true, 8, {4.0, 4.0, 4.0}),
      row("p/fast", true, 8, {2.0, 4.0, 3.0}),
      row("p/broken", true, 8, {}, "failed"),  // failed peers never count as the fastest
      row("tree", false, 32, {5.0}),
      row("p/broken", true, 32, {}, "failed"),  // no peer ran: no ratio at N = 32
  };
  const auto ratios = scalingRatios(rows);
  ASSERT_EQ(ratios.size(), 1u);
  EXPECT_EQ(ratios[0].links, 8);
  EXPECT_EQ(ratios[0].peer, "p/fast");  // median 3 against 4
  ASSERT_EQ(ratios[0].ours.size(), 2u);
  EXPECT_EQ(ratios[0].ours[0].first, "tree");
  // Paired by round, not medians divided: 1/2, 2/4, 3/3.
  EXPECT_EQ(ratios[0].ours[0].second, (std::vector<double>{0.5, 0.5, 1.0}));
  EXPECT_TRUE(ratios[0].ours[1].second.empty());
  EXPECT_EQ(spreadOf(ratios[0].ours[0].second, "%.2f"), "0.50 (0.50-1.00)");
}

TEST(BenchScaling, OurConfigurationsSwingTheChainWithTheirDriftControl) {
  const auto configs = ourScalingConfigs("assets/scenes/chain.json", {"tree"});
  ASSERT_EQ(configs.size(), 3u);
  int labelled = 0;
  for (const auto& c : configs) labelled += c.drift.find("no drift control") != std::string::npos;
  EXPECT_EQ(labelled, 1) << "one row without drift control, labelled as such";
  const auto rows = runScalingSweep(configs, 4, 1, 0.25, 1e9);
  double none = -1.0, held = 0.0;
  for (const auto& r : rows) {
    ASSERT_EQ(r.status, "ok") << r.config << ": " << r.reason;
    if (r.config == "tree/symplectic_euler/none")
      none = r.joint_error;
    else
      held = std::max(held, r.joint_error);
  }
  // Released horizontally, the chain swings: without stabilization its joints drift apart; with
  // projection or RATTLE they hold to their tolerance.
  EXPECT_GT(none, 1e-6);
  EXPECT_LT(held, 1e-9);
}

TEST(BenchScaling, PeerJointErrorIsTheLargestGapBetweenLinkEnds) {
  PeerChain chain;
  chain.length = 0.1;
  std::vector<PeerLink> links(3);
  for (int i = 0; i < 3; ++i) {  // hanging straight down from the anchor at the origin
    links[i].q = Eigen::Quaterniond::Identity();
    links[i].x = Eigen::Vector3d(0.0, 0.0, -0.05 - 0.1 * i);
  }
  EXPECT_NEAR(peerJointError(chain, links), 0.0, 1e-15);
  links[1].x.x() += 0.003;  // both of link 1's joints open by 3 mm
  EXPECT_NEAR(peerJointError(chain, links), 0.003, 1e-12);
  links[0].x.z() -= 0.01;  // link 0 falls off the anchor by 1 cm
  EXPECT_NEAR(peerJointError(chain, links), std::hypot(0.01, 0.003), 1e-12);
}

CostPoint point(const std::string& method, bool peer, double cost, double err, bool bounded = true) {
  return {"c", "chain N=8 fixed", method, peer, 1.0 / 240.0, bounded, cost, err};
}

TEST(BenchEqualAccuracy, TheCheapestBoundedRunOfEachSidePerLevel) {
  const std::vector<CostPoint> points = {
      point("tree/rk4/projection", false, 10.0, 1e-3), point("featherstone/rk4/none", false, 50.0, 1e-5),
      point("tree/rk4/none", false, 5.0, 1e-6, false),  // reaches every level, but its long run blew up
      point("mujoco/RK4", true, 30.0, 5e-4),           point("mujoco/Euler", true, 40.0, 4e-4),
      point("ode/worldstep", true, 1.0, 0.05),
  };
  const auto tables = equalAccuracyTables(points);
  ASSERT_EQ(tables.size(), 1u);
  const EqualAccuracyTable& t = tables[0];
  EXPECT_EQ(t.engines, (std::vector<std::string>{"mujoco", "ode"}));
  ASSERT_EQ(t.levels.size(), 6u);
  // 1e-1 m: ours 10 against ode's 1 (a peer is cheaper).
  EXPECT_EQ(t.levels[0].ours, 0);
  EXPECT_EQ(t.levels[0].peers, (std::vector<int>{3, 5}));
  EXPECT_EQ(t.levels[0].cheapest_peer, 5);
  // 1e-3 m: ode does not reach it; at exactly the level ours does.
  EXPECT_EQ(t.levels[2].ours, 0);
  EXPECT_EQ(t.levels[2].peers, (std::vector<int>{3, -1}));
  // 1e-4 and 1e-5 m: only ours (the dearer, accurate run); 1e-6 m: only the unbounded run, which
  // does not count.
  EXPECT_EQ(t.levels[3].ours, 1);
  EXPECT_EQ(t.levels[3].cheapest_peer, -1);
  EXPECT_EQ(t.levels[5].ours, -1);

  std::ostringstream md;
  writeEqualAccuracySection(md, points, "a test");
  const std::string text = md.str();
  // The first lines say where a peer is cheaper (1e-1 m: 10 against 1), before any table.
  const size_t cheaper = text.find("**Where a peer is cheaper**");
  ASSERT_NE(cheaper, std::string::npos) << text;
  EXPECT_LT(cheaper, text.find("| RMS error at most"));
  EXPECT_NE(text.find("chain N=8 fixed at 0.1 m: ours / ode/worldstep = 10.00"), std::string::npos) << text;
  EXPECT_NE(text.find("| 0.01 | `tree/rk4/projection` 1/240: 0.01 (0.001 m) |"), std::string::npos) << text;
  EXPECT_NE(text.find("| 0.33 |"), std::string::npos) << text;  // 1e-2 m: 10 / 30
}

TEST(BenchEqualAccuracy, ReadsTheSameRunsBackFromBenchCsv) {
  BenchCase c;
  c.id = "chain8_fixed";
  c.title = "chain N=8 fixed";
  c.links = 8;
  c.anchor = "fixed";
  std::vector<BenchRow> rows(3);
  for (auto& r : rows) r.bench_case = &c;
  rows[0].method = "tree/rk4/projection";
  rows[0].stabilization = "projection";
  rows[0].dt = 1.0 / 240.0;
  rows[0].r.us_per_sim_second = 1234.5;
  rows[0].r.err_rms = 4.5e-4;
  rows[1].method = "mujoco/RK4";
  rows[1].stabilization = "-";
  rows[1].dt = 1.0 / 120.0;
  rows[1].r.us_per_sim_second = 99.0;
  rows[1].r.err_rms = 0.02;
  rows[1].r.long_status = "unbounded";
  rows[2].method = "dense/symplectic_euler/none";
  rows[2].r.status = "failed";
  rows[2].r.reason = "t = 1 s, stage 'integrate': unstable, \"quoted\"";
  const std::string path = (std::filesystem::temp_directory_path() / "ponyhop_equal_accuracy_test.csv").string();
  writeBenchCsv(path, rows);
  const std::vector<CostPoint> read = readCostPoints(path);
  std::filesystem::remove(path);
  const std::vector<CostPoint> direct = costPoints(rows);
  ASSERT_EQ(read.size(), 2u);  // the failed run is left out
  ASSERT_EQ(direct.size(), 2u);
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].case_id, direct[i].case_id);
    EXPECT_EQ(read[i].case_title, direct[i].case_title);
    EXPECT_EQ(read[i].method, direct[i].method);
    EXPECT_EQ(read[i].peer, direct[i].peer);
    EXPECT_EQ(read[i].bounded, direct[i].bounded);
    EXPECT_NEAR(read[i].dt, direct[i].dt, 1e-10);  // bench.csv keeps dt to 9 digits
    EXPECT_NEAR(read[i].cost, direct[i].cost, 1e-9);
    EXPECT_NEAR(read[i].err_rms, direct[i].err_rms, 1e-12);
  }
  EXPECT_TRUE(read[1].peer);
  EXPECT_FALSE(read[1].bounded);
}

TEST(BenchEqualAccuracy, AMergeReplacesItsOwnRowsAndKeepsTheRest) {
  // A coarser rotation limit is part of the method's name, the default's is not.
  EXPECT_EQ((Method{"featherstone", "rk4", "none", StepControl::Auto}).name(), "featherstone/rk4/none+auto");
  EXPECT_EQ((Method{"featherstone", "rk4", "none", StepControl::Auto, 10.0}).name(), "featherstone/rk4/none+auto10");
  EXPECT_EQ(methodOverrides({"tree", "rattle", "none", StepControl::Auto, 10.0}, 1.0 / 60.0)[5].value, "10");
  EXPECT_EQ(methodOverrides({"tree", "rattle", "none"}, 1.0 / 60.0)[5].value, "0");

  BenchCase c8, c32;
  c8.id = "chain8_fixed";
  c32.id = "chain32_fixed";
  const auto row = [](const BenchCase& c, const std::string& method, double dt, double cost) {
    BenchRow r;
    r.bench_case = &c;
    r.method = method;
    r.dt = dt;
    r.r.us_per_sim_second = cost;
    r.r.err_rms = 0.01;
    return r;
  };
  const std::string path = (std::filesystem::temp_directory_path() / "ponyhop_merge_test.csv").string();
  writeBenchCsv(path, {row(c8, "tree/rattle/none", 1.0 / 60.0, 1.0), row(c8, "tree/rattle/none", 1.0 / 120.0, 2.0),
                       row(c32, "tree/rattle/none", 1.0 / 60.0, 3.0)});
  // The same case, method and dt replaced; another dt, another case kept; a new method added.
  EXPECT_EQ(mergeBenchCsv(path, {row(c8, "tree/rattle/none", 1.0 / 60.0, 10.0),
                                 row(c8, "featherstone/rk4/none+auto10", 1.0 / 60.0, 20.0)}),
            1u);
  const std::vector<CostPoint> read = readCostPoints(path);
  std::filesystem::remove(path);
  std::vector<std::string> seen;
  for (const CostPoint& p : read)
    seen.push_back(p.case_id + " " + p.method + " " + fmt(1.0 / p.dt, "%.0f") + " " + fmt(p.cost));
  EXPECT_EQ(seen, (std::vector<std::string>{
                      "chain8_fixed tree/rattle/none 120 2", "chain32_fixed tree/rattle/none 60 3",
                      "chain8_fixed tree/rattle/none 60 10", "chain8_fixed featherstone/rk4/none+auto10 60 20"}));
}

}  // namespace
}  // namespace ponyhop

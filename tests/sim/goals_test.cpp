// Goals and the goal solve (sim/goal_solve.h, docs/GOALS.md) on a 3-link chain hanging from a fixed
// anchor: the scene fields and their errors, the guide's curve, the gradient check, zero effort for
// a goal the unguided motion meets, an unreachable goal said so, and a solved scene's replay.
#include <gtest/gtest.h>

#include <algorithm>

#include "cube_head.h"
#include "sim/goal_solve.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

using nlohmann::json;

// Three links of 5 cm released horizontally: a fast, smooth motion.
Scene chainScene() {
  return parseSceneText(R"({"anchor": {}, "chain": {"links": 3, "direction": [1, 0, 0]}})", "three.json");
}

std::string errorOf(const std::string& text) {
  try {
    parseSceneText(text, "goals.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Where the unguided tip is at t.
Eigen::Vector3d tipAt(const Scene& scene, double t) {
  Sim sim(scene);
  sim.advanceTo(t);
  return sim.chain()->tip(sim.world());
}

TEST(Goals, FieldsRoundTrip) {
  const Scene s = parseSceneText(R"({"anchor": {}, "chain": {"links": 3},
      "goals": [{"t": 0.3, "point": "link:1", "position": [0.01, 0, -0.08], "tolerance": 0.002, "weight": 2}],
      "guide": {"enabled": false, "knots": [{"joint": 2, "t": 0, "torque": [0, 0.001, 0]}, {"joint": 2, "t": 0.5}]}})",
                                 "goals.json");
  ASSERT_EQ(s.goals.size(), 1u);
  EXPECT_EQ(s.goals[0].point, "link:1");
  EXPECT_DOUBLE_EQ(s.goals[0].weight, 2.0);
  ASSERT_TRUE(s.guide);
  EXPECT_FALSE(s.guide->enabled);
  const Scene again = parseScene(sceneToJson(s), "again.json");
  EXPECT_EQ(sceneToJson(again), sceneToJson(s));
  // --set reaches a goal by index.
  const Scene moved = parseSceneText(R"({"anchor": {}, "chain": {"links": 3}, "goals": [{"t": 0.3}]})", "goals.json",
                                     {parseOverride("goals.0.position=[0,0,-0.1]")});
  EXPECT_DOUBLE_EQ(moved.goals[0].position.z(), -0.1);
}

TEST(Goals, BadInputNamesTheField) {
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "goals": [{"point": "nose"}]})")
                .find("goals.0.point: \"nose\" must be tip, link:K"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {"links": 3}, "goals": [{"point": "link:7"}]})")
                .find("goals.0.point: \"link:7\": the chain has links 0..2"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "goals": [{"frame": "head"}]})")
                .find("goals.0.frame: \"head\" needs a head"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"goals": [{"point": "tip"}]})").find("needs a chain section"), std::string::npos);
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "goals": [{"point": "toe"}]})").find("needs a hopper section"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "goals": [{"tolerance": 0}]})").find("goals.0.tolerance: must be"),
            std::string::npos);
  EXPECT_NE(
      errorOf(R"({"anchor": {}, "chain": {"links": 3}, "guide": {"knots": [{"joint": 3}, {"joint": 3, "t": 1}]}})")
          .find("guide.knots.0.joint: 3 is not a joint of the chain (0..2)"),
      std::string::npos);
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "guide": {"knots": [{"joint": 0}]}})").find("has one knot"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "guide": {"knots": [{"t": 1}, {"t": 1}]}})").find("two knots at t"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"guide": {}})").find("guide: needs a chain section"), std::string::npos);
  // The hopper's solved commands (guide.script).
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "guide": {"script": [{"t": 0}]}})")
                .find("guide.script: needs a hopper section"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"hopper": {}, "guide": {"script": [{"t": 1}, {"t": 0.5}]}})")
                .find("guide.script.1.t = 0.500000 s: keys must be in increasing time order"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"hopper": {}, "guide": {"script": [{"t": 0, "vx": 9}]}})").find("guide.script.0.vx"),
            std::string::npos);
  EXPECT_NE(
      errorOf(R"({"hopper": {}, "guide": {"knots": [{"t": 0}, {"t": 1}]}})").find("guide.knots: needs a chain section"),
      std::string::npos);
  EXPECT_NE(errorOf(R"({"anchor": {}, "chain": {}, "render": {"goals": "yes"}})").find("render.goals"),
            std::string::npos);
}

// What the markers of render.goals are drawn from: the goal's point and its target now.
TEST(Goals, PointAndTargetNow) {
  Scene s = parseSceneText(R"({"anchor": {}, "chain": {"links": 3, "direction": [1, 0, 0]},
      "goals": [{"t": 0.2, "point": "link:0", "position": [0.01, 0.02, -0.03]}]})",
                           "now.json");
  s.goals.push_back(s.goals[0]);
  s.goals[1].point = "toe";  // no hopper: no point
  Sim sim(s);
  sim.advanceTo(0.1);
  Eigen::Vector3d p;
  ASSERT_TRUE(goalPointNow(sim, s.goals[0], p));
  EXPECT_EQ(p, sim.chain()->bottom(sim.world(), 0));
  EXPECT_EQ(goalTargetNow(sim, s.goals[0]), Eigen::Vector3d(0.01, 0.02, -0.03));
  EXPECT_FALSE(goalPointNow(sim, s.goals[1], p));
}

TEST(Goals, GuideCurveInterpolatesItsKnotsAndIsZeroOutside) {
  const std::vector<double> times{0.0, 0.2, 0.5, 0.6};
  const std::vector<double> values{1.0, -2.0, 0.5, 3.0};
  std::array<double, 4> w;
  const auto eval = [&](double t) {
    const int i = guideWeights(times, t, w);
    double v = 0.0;
    for (int k = 0; k < 4; ++k)
      if (i >= 0 && i - 1 + k >= 0 && i - 1 + k < 4) v += w[size_t(k)] * values[size_t(i - 1 + k)];
    return v;
  };
  for (size_t k = 0; k < times.size(); ++k) EXPECT_NEAR(eval(times[k]), values[k], 1e-14);
  EXPECT_EQ(eval(-0.01), 0.0);
  EXPECT_EQ(eval(0.61), 0.0);
  // C1 at an inner knot: the slopes from both sides agree.
  const double e = 1e-7;
  EXPECT_NEAR((eval(0.2) - eval(0.2 - e)) / e, (eval(0.2 + e) - eval(0.2)) / e, 1e-4);
}

// The solve's forward differences against central differences and their Richardson extrapolation
// (error O(h^4)) on the 3-link chain: the gradient to 1e-6 relative.
TEST(Goals, GradientMatchesExtrapolatedDifferences) {
  Scene s = chainScene();
  s.goals = {Goal{.t = 0.25, .point = "tip"}, Goal{.t = 0.15, .point = "link:0"}};
  const int knots = 3;
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(3 * knots * 3, 2e-4);
  // Steps of 1e-6 N m and more reach a discontinuity of the step (most likely a substep split of
  // the step control, physics.max_step_rotation): the differences then see a jump as a slope
  // (2 % off at 1e-6). At 1e-7 they agree (docs/GOALS.md).
  const Eigen::MatrixXd central = goalJacobian(s, nullptr, knots, c, 1e-7, true);
  const Eigen::MatrixXd central2 = goalJacobian(s, nullptr, knots, c, 2e-7, true);
  const Eigen::MatrixXd richardson = (4.0 * central - central2) / 3.0;
  const double scale = richardson.norm();
  ASSERT_GT(scale, 1.0);  // m per N m: the torques move the chain
  EXPECT_LT((central - richardson).norm() / scale, 1e-6);
  const Eigen::MatrixXd forward = goalJacobian(s, nullptr, knots, c, 1e-7, false);
  EXPECT_LT((forward - richardson).norm() / scale, 1e-4);  // forward differences, O(h)
  // The root joint's first knot moves the root link's goal.
  EXPECT_GT(richardson.block(3, 0, 3, 3).norm(), 0.0);
}

// An independent derivation: a straight 3-link chain at rest without gravity, springs, damping or
// drag. To first order in the torques (the velocity terms are quadratic) the links' small rotation
// vectors phi_i obey M phi'' = P tau(t), with the mass matrix M = sum_i m_i C_i^T C_i + diag(I_i)
// from the kinetic energy (C_i: the centre of link i moved by phi, sum_{j<i} L phi_j x d +
// L/2 phi_i x d) and P the joint pairs (tau_j on link j, -tau_j on link j - 1: Q_i = tau_i -
// tau_{i+1}). From rest, phi(T) = M^-1 P integral_0^T (T - s) tau(s) ds, and with
// tau_j(s) = sum_k B_k(s) c_jk the tip's Jacobian is C_tip M^-1 P_(j) integral_0^T (T - s) B_k(s) ds,
// the integral exact by Gauss-Legendre (a quartic per knot interval). The differences through the
// whole simulation (RK4, the joints as constraints) must agree with it to 1e-6 relative.
TEST(Goals, GradientMatchesLinearizedDynamicsDerivedByHand) {
  Scene s = parseSceneText(R"({"anchor": {}, "chain": {"links": 3, "direction": [1, 0, 0]},
      "physics": {"gravity": [0, 0, 0], "integrator": "rk4", "substeps": 2}})",
                           "still.json");
  const double T = 0.25;
  s.goals = {Goal{.t = T, .point = "tip"}};
  const int knots = 3, n = 3;
  const double L = s.chain->length;
  const Eigen::MatrixXd fd = goalJacobian(s, nullptr, knots, Eigen::VectorXd::Zero(3 * knots * n), 1e-9, true);

  Sim sim(s);
  const Eigen::Vector3d d(1.0, 0.0, 0.0);
  Eigen::Matrix3d S;  // S phi = phi x d
  S << 0, d.z(), -d.y(), -d.z(), 0, d.x(), d.y(), -d.x(), 0;
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(3 * n, 3 * n), P = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  Eigen::MatrixXd tip = Eigen::MatrixXd::Zero(3, 3 * n);
  for (int i = 0; i < n; ++i) {
    const RigidBody& b = sim.world().body(sim.chain()->links[size_t(i)]);
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(3, 3 * n);
    for (int j = 0; j < i; ++j) C.middleCols<3>(3 * j) = L * S;
    C.middleCols<3>(3 * i) = 0.5 * L * S;
    M += b.mass * C.transpose() * C;
    M.block<3, 3>(3 * i, 3 * i) += b.worldInertia();
    tip.middleCols<3>(3 * i) = L * S;
    P.block<3, 3>(3 * i, 3 * i) = Eigen::Matrix3d::Identity();
    if (i + 1 < n) P.block<3, 3>(3 * i, 3 * (i + 1)) = -Eigen::Matrix3d::Identity();
  }
  const Eigen::MatrixXd response = tip * M.inverse() * P;  // tip displacement per unit of integral (T-s) tau
  // The knots of goalJacobian's layout: t_k = k T / (K - 1), one more (zero) at K T / (K - 1).
  std::vector<double> times;
  for (int k = 0; k <= knots; ++k) times.push_back(k * T / (knots - 1));
  static const double xs[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
  static const double ws[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
  Eigen::VectorXd moment = Eigen::VectorXd::Zero(knots);  // integral_0^T (T - s) B_k(s) ds
  for (int i = 0; i + 1 < knots; ++i) {
    const double a = times[size_t(i)], b = times[size_t(i + 1)];
    for (int q = 0; q < 4; ++q) {
      const double t = 0.5 * (a + b) + 0.5 * (b - a) * xs[q];
      std::array<double, 4> w;
      const int interval = guideWeights(times, t, w);
      for (int p = 0; p < 4; ++p) {
        const int k = interval - 1 + p;
        if (k >= 0 && k < knots) moment[k] += 0.5 * (b - a) * ws[q] * (T - t) * w[size_t(p)];
      }
    }
  }
  Eigen::MatrixXd analytic(3, 3 * knots * n);
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < knots; ++k)
      analytic.middleCols<3>((j * knots + k) * 3) = response.middleCols<3>(3 * j) * moment[k];
  ASSERT_GT(analytic.norm(), 1.0);
  const double relative = (fd - analytic).norm() / analytic.norm();
  EXPECT_LT(relative, 1e-6) << "relative " << relative << "\ndifferences\n" << fd << "\nderived\n" << analytic;
}

TEST(Goals, GoalMetUnguidedNeedsZeroEffort) {
  Scene s = chainScene();
  s.goals = {Goal{.t = 0.2, .point = "tip", .position = tipAt(s, 0.2)}};
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 3});
  EXPECT_TRUE(r.all_met);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(r.effort, 0.0);
}

TEST(Goals, UnreachableGoalIsReported) {
  Scene s = chainScene();
  s.goals = {Goal{.t = 0.2, .point = "tip", .position = {0.0, 0.0, -0.5}}};  // 0.5 m from the anchor; 0.15 m of chain
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 3});
  EXPECT_FALSE(r.all_met);
  EXPECT_NE(r.goals[0].why.find("beyond the chain's reach"), std::string::npos) << r.goals[0].why;
  EXPECT_NE(r.goals[0].why.find("the closest any control gets is 350.00 mm"), std::string::npos) << r.goals[0].why;
}

// Sequential windows: two goals met in time order, each by the torques within `window` before
// it; no torque acts before the first window.
TEST(Goals, WindowsMeetGoalsInTimeOrder) {
  Scene s = chainScene();
  s.goals = {Goal{.t = 0.35, .point = "tip", .position = tipAt(s, 0.35) + Eigen::Vector3d(0.0, -0.01, 0.005)},
             Goal{.t = 0.25, .point = "tip", .position = tipAt(s, 0.25) + Eigen::Vector3d(0.0, 0.01, 0.0)}};
  // Knots every 0.025 s; windows [0.05, 0.25) and, as 0.35 - 0.2 is before the first goal,
  // [0.25 + dt, 0.35).
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 15, .window = 0.2});
  ASSERT_TRUE(r.all_met) << r.goals[0].error << " " << r.goals[1].error;
  s.guide = r.guide;
  Sim guided(s);
  for (double t = 0.0; t < 0.05 - 1e-9; t += 0.01) EXPECT_EQ(guided.guide()->torque(0, t).norm(), 0.0) << t;
  EXPECT_GT(guided.guide()->torque(0, 0.2).norm(), 0.0);
}

// The adaptive window: a goal 3 cm off the unguided tip is out of reach of the torques of the
// last 0.05 s before it (the solve stops short of it with --fixed-window), and met once the window
// has doubled toward the start.
TEST(Goals, AdaptiveWindowWidensUntilTheGoalIsMet) {
  Scene s = chainScene();
  s.goals = {Goal{.t = 0.3, .point = "tip", .position = tipAt(s, 0.3) + Eigen::Vector3d(0.0, 0.03, 0.0)}};
  GoalSolveOptions o{.knots = 13, .window = 0.07, .adaptive_window = false, .max_iterations = 6};
  const GoalSolveReport fixed = solveGoals(s, nullptr, o);
  EXPECT_FALSE(fixed.all_met) << fixed.goals[0].error;
  o.adaptive_window = true;
  const GoalSolveReport adaptive = solveGoals(s, nullptr, o);
  EXPECT_TRUE(adaptive.all_met) << adaptive.goals[0].error << " " << adaptive.goals[0].why;
  const bool widened = std::any_of(adaptive.log.begin(), adaptive.log.end(),
                                   [](const std::string& l) { return l.find("window widened") != std::string::npos; });
  EXPECT_TRUE(widened);
}

TEST(Goals, SolvedSceneMeetsItsGoalAndReplaysFromTheFile) {
  Scene s = chainScene();
  const Eigen::Vector3d free_tip = tipAt(s, 0.25);
  s.goals = {Goal{.t = 0.25, .point = "tip", .position = free_tip + Eigen::Vector3d(0.0, 0.02, 0.01)}};
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 4});
  ASSERT_TRUE(r.all_met) << r.goals[0].error;
  EXPECT_GT(r.effort, 0.0);
  s.guide = r.guide;
  const Scene saved = parseScene(sceneToJson(s), "solved.json");
  const GoalSolveReport replay = evaluateGoals(saved, nullptr);
  EXPECT_EQ(replay.goals[0].error, r.goals[0].error);  // bit for bit: the file keeps every digit
  // One toggle away: the unguided motion again.
  Scene off = saved;
  off.guide->enabled = false;
  EXPECT_EQ(evaluateGoals(off, nullptr).goals[0].reached, free_tip);
}

// The hopper (sim/hopper_goal_solve.h): from rest, commanded 0.5 m/s along x; its second landing
// puts the toe at about (0.12, 0, 0) from 1.3 to 1.5 s.
Scene hopperScene() {
  return parseSceneText(
      R"({"physics": {"dt": 0.001, "integrator": "rk4", "stabilization": "projection"},
          "hopper": {"position": [0, 0, 1.05], "command": {"vx": 0.5}}})",
      "hop.json");
}

Eigen::Vector3d toeAt(const Scene& scene, double t) {
  Sim sim(scene);
  sim.advanceTo(t);
  return sim.hopper()->footPoint(sim.world());
}

TEST(HopperGoals, AMarkTheHopperAlreadyLandsOnNeedsNoChange) {
  Scene s = hopperScene();
  s.goals = {Goal{.t = 1.4, .point = "toe", .position = toeAt(s, 1.4), .tolerance = 0.02}};
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 3});
  EXPECT_TRUE(r.all_met) << r.goals[0].error;
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(r.effort, 0.0);
  EXPECT_TRUE(r.guide.script.empty()) << "the scene's own commands: nothing to write";
}

// A mark 6 cm from the unguided landing, met by the commands (the toe within the goal's 2 cm), and
// the solved scene replays it from the file, bit for bit; guide.enabled = false is the unguided run.
TEST(HopperGoals, TheToeLandsOnAMarkAndTheSolvedSceneReplaysIt) {
  Scene s = hopperScene();
  s.hopper->script = {HopperCommandKey{.t = 3.0, .vx = 0.0}};  // the scene's own course: a stop after the goal
  const Eigen::Vector3d free_toe = toeAt(s, 1.4);
  s.goals = {
      Goal{.t = 1.4, .point = "toe", .position = free_toe + Eigen::Vector3d(0.05, 0.03, 0.0), .tolerance = 0.02}};
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 3});
  ASSERT_TRUE(r.all_met) << r.goals[0].error << " " << r.goals[0].why;
  EXPECT_GT(r.iterations, 0);
  EXPECT_GT(r.effort, 0.0);
  ASSERT_FALSE(r.guide.script.empty());
  EXPECT_EQ(r.guide.script.back().t, 3.0) << "after the last goal the scene's own course goes on";
  EXPECT_EQ(r.guide.script.back().vx, 0.0);
  EXPECT_TRUE(r.guide.knots.empty()) << "no chain: no torques";
  s.guide = r.guide;
  const Scene saved = parseScene(sceneToJson(s), "solved.json");
  const GoalSolveReport replay = evaluateGoals(saved, nullptr);
  EXPECT_EQ(replay.goals[0].error, r.goals[0].error);
  EXPECT_DOUBLE_EQ(replay.effort, r.effort);
  Scene off = saved;
  off.guide->enabled = false;
  EXPECT_LT((evaluateGoals(off, nullptr).goals[0].reached - free_toe).norm(), 1e-12);
}

// What film tools would do instead: a spring pulling the toe to the mark meets it, at a cost in
// work far beyond what steering the controller asks of the hopper's own muscles.
TEST(HopperGoals, AGoalSpringPullsTheToeAndCostsMoreThanTheCommands) {
  Scene s = hopperScene();
  s.goals = {
      Goal{.t = 1.4, .point = "toe", .position = toeAt(s, 1.4) + Eigen::Vector3d(0.05, 0.03, 0.0), .tolerance = 0.02}};
  const SpringOutcome spring = springGoals(s, nullptr, 1e4);
  EXPECT_TRUE(spring.all_met) << spring.goals[0].error;
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 3});
  ASSERT_TRUE(r.all_met);
  // The muscles' work beyond the scene's own course (it can be less: here -5.9 J of |power|).
  EXPECT_NE(r.abs_energy, 0.0) << "the muscles' extra work is measured";
  EXPECT_LT(std::abs(r.abs_energy), 0.5 * spring.abs_work);
}

// A mark in the head's frame rides on the keyframed head: the solve compares the toe with where
// the head carries the mark at the goal's time, not with the head-frame numbers as a world point.
TEST(HopperGoals, AMarkInTheHeadsFrameIsWhereTheHeadCarriesIt) {
  const CubeAssets cube;
  Scene s = parseSceneText(
      R"({"physics": {"dt": 0.001, "integrator": "rk4", "stabilization": "projection"},
          "hopper": {"position": [0, 0, 1.05], "command": {"vx": 0.5}},
          "head": {"animation": {"keys": [{"t": 0, "position": [0, 0, 1.6], "rotation": [0, 0, 0]},
                                          {"t": 2, "position": [0.4, 0.1, 1.7], "rotation": [0, 0, 60]}]}}})",
      "hop_head.json");
  Sim sim(s, &cube);
  sim.advanceTo(1.4);
  const Eigen::Vector3d toe = sim.hopper()->footPoint(sim.world());
  const RigidBody& head = sim.world().body(sim.headBody());
  const Eigen::Vector3d in_head = head.q.conjugate() * (toe - head.x);
  ASSERT_GT((in_head - toe).norm(), 0.5) << "the two frames must differ for the test to mean anything";
  s.goals = {Goal{.t = 1.4, .point = "toe", .position = in_head, .frame = GoalFrame::Head, .tolerance = 0.02}};
  const GoalSolveReport r = solveGoals(s, &cube, {.knots = 3});
  EXPECT_TRUE(r.all_met) << r.goals[0].error;
  EXPECT_EQ(r.iterations, 0) << "the unguided landing is already on the mark";
  EXPECT_LT((r.goals[0].target - toe).norm(), 1e-9);
}

TEST(HopperGoals, AMarkOutOfReachIsReportedWithWhatStoppedIt) {
  Scene s = hopperScene();
  s.goals = {Goal{.t = 1.0, .point = "toe", .position = {20.0, 0.0, 0.0}, .tolerance = 0.02}};
  const GoalSolveReport r = solveGoals(s, nullptr, {.knots = 2, .max_iterations = 4});
  EXPECT_FALSE(r.all_met);
  const std::string& why = r.goals[0].why;
  EXPECT_NE(why.find("the closest the hopper's commands got is"), std::string::npos) << why;
  EXPECT_TRUE(why.find("at its bound") != std::string::npos || why.find("fall") != std::string::npos ||
              why.find("iteration limit") != std::string::npos ||
              why.find("lowered the goal error") != std::string::npos)
      << why;
}

}  // namespace
}  // namespace ponyhop

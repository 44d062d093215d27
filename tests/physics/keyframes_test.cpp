// The head's keyframe track (physics/models/keyframes.h): analytic derivatives against finite
// differences, C2 continuity across keys, interpolation, loop seams, clamping, unwrapping of
// spins, input validation, and the shipped clips (assets/animations/*.json).
#include "physics/models/keyframes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

using namespace ponyhop;
using Eigen::Quaterniond;
using Eigen::Vector3d;

namespace {

constexpr double kPi = std::numbers::pi;

// Rotation vector of q (angle in [0, pi]).
Vector3d logQ(Quaterniond q) {
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  const double s = q.vec().norm();
  if (s < 1e-300) return Vector3d::Zero();
  return q.vec() * (2.0 * std::atan2(s, q.w()) / s);
}

// A lively clip: non-uniform spacing, large rotations about several axes, translation.
std::vector<Keyframe> busyKeys() {
  return {
      {0.0, {0.0, 0.0, 0.35}, {0, 0, 0}},       {0.4, {0.02, -0.01, 0.37}, {25, 5, -10}},
      {0.7, {0.05, 0.00, 0.33}, {-20, 15, 60}}, {1.5, {-0.03, 0.04, 0.40}, {10, -30, 120}},
      {1.8, {0.00, 0.02, 0.36}, {40, 10, 170}}, {2.6, {0.01, -0.02, 0.35}, {-35, 0, 30}},
  };
}

KeyframeTrack mustBuild(const std::vector<Keyframe>& keys, TrackOptions opt) {
  KeyframeTrack tr;
  const Status s = KeyframeTrack::fromKeyframes(keys, opt, tr);
  EXPECT_TRUE(s.ok()) << s.message();
  if (!s.ok()) std::abort();
  return tr;
}

// Times at and around every key and in between, plus random ones, spanning [a, b].
std::vector<double> probeTimes(const std::vector<Keyframe>& keys, double speed, double a, double b) {
  std::vector<double> ts;
  for (const Keyframe& k : keys) {
    for (double off : {0.0, 1e-4, -1e-4, 3e-3, -3e-3}) ts.push_back(k.t / speed + off);
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(a, b);
  for (int i = 0; i < 200; ++i) ts.push_back(u(rng));
  return ts;
}

void expectNear3(const Vector3d& got, const Vector3d& want, double tol, const std::string& what, double t) {
  EXPECT_LE((got - want).norm(), tol) << what << " at t = " << t << ": got " << got.transpose() << ", want "
                                      << want.transpose();
}

// v, a against central differences of x and of the analytic v; w against the central difference
// of q (log(q(t+h) q(t-h)^-1) / 2h, world frame); alpha against the difference of the analytic w.
void checkDerivatives(const KeyframeTrack& tr, const std::vector<double>& times) {
  const double h = 1e-6;
  for (double t : times) {
    const KinematicState s = tr.evaluate(t), p = tr.evaluate(t + h), m = tr.evaluate(t - h);
    const double tolV = 1e-5 * (1.0 + s.v.norm());
    const double tolA = 2e-4 * (1.0 + s.a.norm());
    expectNear3(s.v, (p.x - m.x) / (2 * h), tolV, "v", t);
    expectNear3(s.a, (p.v - m.v) / (2 * h), tolA, "a", t);
    expectNear3(s.w, logQ(p.q * m.q.conjugate()) / (2 * h), 1e-5 * (1.0 + s.w.norm()), "w", t);
    expectNear3(s.alpha, (p.w - m.w) / (2 * h), 2e-4 * (1.0 + s.alpha.norm()), "alpha", t);
    EXPECT_NEAR(s.q.norm(), 1.0, 1e-12);
  }
}

}  // namespace

TEST(Keyframes, ExpRotationVectorDerivativesAtAndNearZero) {
  // r(t) = a t + b t^2 / 2 passes through 0 at t = 0 (series branch) and crosses |r| = 0.1 (the
  // switch between series and closed forms) near t = 0.1 / |a|.
  const Vector3d a(0.8, -0.3, 0.5), b(-2.0, 1.0, 3.0);
  auto r = [&](double t) { return Vector3d(a * t + 0.5 * b * t * t); };
  auto dr = [&](double t) { return Vector3d(a + b * t); };
  const double tSwitch = 0.1 / a.norm();
  for (double t : {0.0, 1e-9, -1e-4, 2e-3, 0.05, tSwitch - 1e-7, tSwitch, tSwitch + 1e-7, 0.7, 3.0, 5.5}) {
    const QuatJet j = expRotationVector(r(t), dr(t), b);
    const double h = 1e-5;
    const QuatJet jp = expRotationVector(r(t + h), dr(t + h), b), jm = expRotationVector(r(t - h), dr(t - h), b);
    const Eigen::Vector4d fd1 = (jp.q.coeffs() - jm.q.coeffs()) / (2 * h);
    const Eigen::Vector4d fd2 = (jp.dq.coeffs() - jm.dq.coeffs()) / (2 * h);
    // Central differences err by ~h^2 |d3q/dt3| ~ h^2 |r'|^3.
    const double tol = 1e-9 * (1.0 + std::pow(dr(t).norm(), 3));
    EXPECT_LE((j.dq.coeffs() - fd1).norm(), tol) << "t = " << t;
    EXPECT_LE((j.ddq.coeffs() - fd2).norm(), tol) << "t = " << t;
    // The value is the rotation of angle |r| about r/|r|.
    const Vector3d rv = r(t);
    const Quaterniond ref =
        rv.norm() > 0 ? Quaterniond(Eigen::AngleAxisd(rv.norm(), rv.normalized())) : Quaterniond::Identity();
    EXPECT_LE((j.q.coeffs() - ref.coeffs()).norm(), 1e-14) << "t = " << t;
  }
}

TEST(Keyframes, DerivativesMatchFiniteDifferencesClamp) {
  const auto keys = busyKeys();
  const KeyframeTrack tr = mustBuild(keys, {LoopMode::Clamp, 1.3, 0.8});
  checkDerivatives(tr, probeTimes(keys, 1.3, -0.5, 3.0));
}

TEST(Keyframes, DerivativesMatchFiniteDifferencesLoop) {
  const auto keys = busyKeys();  // last != first: closed automatically
  const KeyframeTrack tr = mustBuild(keys, {LoopMode::Loop, 0.7, 1.2});
  checkDerivatives(tr, probeTimes(keys, 0.7, -2.0, 12.0));
}

// Left and right limits of the acceleration and the angular acceleration agree at every key and
// at every interval midpoint (where clamp mode puts its free knots). A C1 curve (Catmull-Rom,
// Hermite, SQUAD) fails this by jumps of order |a|.
TEST(Keyframes, AccelerationIsContinuousAcrossKeys) {
  const auto keys = busyKeys();
  for (LoopMode mode : {LoopMode::Clamp, LoopMode::Loop}) {
    const KeyframeTrack tr = mustBuild(keys, {mode, 1.0, 1.0});
    std::vector<double> ts;
    for (size_t i = 0; i < keys.size(); ++i) {
      ts.push_back(keys[i].t);
      if (i + 1 < keys.size()) ts.push_back(0.5 * (keys[i].t + keys[i + 1].t));
    }
    if (mode == LoopMode::Loop) ts.push_back(tr.startTime() + tr.period());  // the seam
    const double d = 1e-7;
    for (double t : ts) {
      const KinematicState l = tr.evaluate(t - d), r = tr.evaluate(t + d);
      expectNear3(l.a, r.a, 1e-4 * (1 + l.a.norm()), "a jump", t);
      expectNear3(l.alpha, r.alpha, 1e-4 * (1 + l.alpha.norm()), "alpha jump", t);
      // v and w change by ~2d |a| between the two probes.
      expectNear3(l.v, r.v, 1e-6 + 4 * d * l.a.norm(), "v jump", t);
      expectNear3(l.w, r.w, 1e-6 + 4 * d * l.alpha.norm(), "w jump", t);
    }
  }
}

TEST(Keyframes, PassesThroughKeysWithAmplitude) {
  const auto keys = busyKeys();
  for (LoopMode mode : {LoopMode::Clamp, LoopMode::Loop}) {
    for (double amp : {1.0, 0.5}) {
      const KeyframeTrack tr = mustBuild(keys, {mode, 2.0, amp});
      const Quaterniond q0 = eulerDegToQuat(keys[0].rotation);
      for (const Keyframe& k : keys) {
        const KinematicState s = tr.evaluate(k.t / 2.0);
        expectNear3(s.x, keys[0].position + amp * (k.position - keys[0].position), 1e-9, "x at key", k.t);
        // amplitude scales the rotation vector of q0^-1 q_i (all keys here are within 180 deg of key 0)
        const Vector3d rel = logQ(q0.conjugate() * eulerDegToQuat(k.rotation));
        const Quaterniond want = q0 * Quaterniond(Eigen::AngleAxisd(amp * rel.norm(), rel.normalized()));
        EXPECT_LE(s.q.angularDistance(k.t == 0 ? q0 : want), 1e-9) << "key at t = " << k.t << " amp " << amp;
      }
    }
  }
}

TEST(Keyframes, EulerConventionIsRzRyRx) {
  const Vector3d deg(30, -20, 75);
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(75 * kPi / 180, Vector3d::UnitZ()) * Eigen::AngleAxisd(-20 * kPi / 180, Vector3d::UnitY()) *
       Eigen::AngleAxisd(30 * kPi / 180, Vector3d::UnitX()))
          .toRotationMatrix();
  EXPECT_LE((eulerDegToQuat(deg).toRotationMatrix() - R).norm(), 1e-14);
  // A nod about x tips the face (-y) downward (-z) for a positive angle.
  EXPECT_LT((eulerDegToQuat({20, 0, 0}) * Vector3d(0, -1, 0)).z(), -0.3);
}

TEST(Keyframes, LoopIsPeriodicAtTheSeam) {
  auto keys = busyKeys();
  keys.push_back({3.1, keys[0].position, keys[0].rotation + Vector3d(0, 0, 0)});  // explicit closing key
  const KeyframeTrack tr = mustBuild(keys, {LoopMode::Loop, 1.0, 1.0});
  EXPECT_NEAR(tr.period(), 3.1, 1e-12);
  for (double t : {0.0, 1e-6, 0.3, 1.77, 3.1 - 1e-6}) {
    for (int k : {-2, 1, 3}) {
      const KinematicState a = tr.evaluate(t), b = tr.evaluate(t + k * 3.1);
      expectNear3(a.x, b.x, 1e-9, "x periodic", t);
      expectNear3(a.v, b.v, 1e-8, "v periodic", t);
      expectNear3(a.a, b.a, 1e-7, "a periodic", t);
      EXPECT_LE(a.q.angularDistance(b.q), 1e-9);
      expectNear3(a.w, b.w, 1e-8, "w periodic", t);
      expectNear3(a.alpha, b.alpha, 1e-7, "alpha periodic", t);
    }
  }
  // Seam: the end of one period joins the start of the next in value, slope and curvature.
  const double d = 1e-7;
  const KinematicState l = tr.evaluate(3.1 - d), r = tr.evaluate(3.1 + d);
  expectNear3(l.x, r.x, 1e-6, "x seam", 3.1);
  expectNear3(l.v, r.v, 1e-6 + 4 * d * l.a.norm(), "v seam", 3.1);
  expectNear3(l.a, r.a, 1e-4 * (1 + l.a.norm()), "a seam", 3.1);
  expectNear3(l.w, r.w, 1e-6 + 4 * d * l.alpha.norm(), "w seam", 3.1);
  expectNear3(l.alpha, r.alpha, 1e-4 * (1 + l.alpha.norm()), "alpha seam", 3.1);
  EXPECT_GT(l.a.norm() + l.alpha.norm(), 0.1);  // the seam is not trivially at rest
}

TEST(Keyframes, LoopClosesAutomaticallyOneMeanSpacingAfterTheLastKey) {
  const auto keys = busyKeys();  // 6 keys over 2.6 s: mean spacing 0.52 s
  const KeyframeTrack tr = mustBuild(keys, {LoopMode::Loop, 1.0, 1.0});
  EXPECT_NEAR(tr.period(), 2.6 + 0.52, 1e-12);
  const KinematicState s = tr.evaluate(3.12);
  expectNear3(s.x, keys[0].position, 1e-9, "closing key", 3.12);
  EXPECT_LE(s.q.angularDistance(Quaterniond::Identity()), 1e-9);
}

TEST(Keyframes, ClampHoldsBeforeAndAfterWithZeroDerivatives) {
  auto keys = busyKeys();
  for (auto& k : keys) k.t += 0.5;  // first key at 0.5 s: before it the first pose is held
  const KeyframeTrack tr = mustBuild(keys, {LoopMode::Clamp, 1.0, 1.0});
  for (double t : {-3.0, 0.0, 0.5, 3.1, 10.0, 1e5}) {
    const KinematicState s = tr.evaluate(t);
    const Keyframe& k = t <= 0.5 ? keys.front() : keys.back();
    expectNear3(s.x, k.position, 1e-12, "held x", t);
    EXPECT_LE(s.q.angularDistance(eulerDegToQuat(k.rotation)), 1e-9) << t;
    EXPECT_EQ(s.v.norm() + s.a.norm() + s.w.norm() + s.alpha.norm(), 0.0) << t;
  }
  // The curve runs into the held pose with v = 0 and a = 0 (no jump in acceleration).
  for (double t : {0.5 + 1e-6, 3.1 - 1e-6}) {
    const KinematicState s = tr.evaluate(t);
    EXPECT_LE(s.v.norm() + s.w.norm(), 1e-4) << t;
    EXPECT_LE(s.a.norm() + s.alpha.norm(), 1e-3) << t;
  }
  // ... and really moves in between.
  EXPECT_GT(tr.evaluate(1.5).v.norm(), 0.01);
}

TEST(Keyframes, SingleKeyIsAConstantPose) {
  const std::vector<Keyframe> one{{1.0, {0.1, 0.2, 0.3}, {10, 20, 30}}};
  for (LoopMode mode : {LoopMode::Clamp, LoopMode::Loop}) {
    const KeyframeTrack tr = mustBuild(one, {mode, 1.0, 1.0});
    for (double t : {-1.0, 0.0, 1.0, 2.5}) {
      const KinematicState s = tr.evaluate(t);
      expectNear3(s.x, one[0].position, 1e-15, "x", t);
      EXPECT_LE(s.q.angularDistance(eulerDegToQuat(one[0].rotation)), 1e-12);
      EXPECT_EQ(s.v.norm() + s.a.norm() + s.w.norm() + s.alpha.norm(), 0.0);
    }
  }
}

// Two 360 degree turns about z, keyed every 90 deg (exactly where a naive slerp/log would be
// ambiguous at 180 deg) and every 170 deg: the yaw rate never reverses and the head ends two
// turns later; the keyed orientations are met on the way.
TEST(Keyframes, SpinOf720DegreesUnwrapsWithoutFlips) {
  for (double step : {90.0, 170.0, 45.0}) {
    std::vector<Keyframe> keys;
    double deg = 0;
    for (int i = 0; deg < 720.0 - 1e-9; ++i) {
      deg = std::min(720.0, i * step);
      keys.push_back({i * 0.25, {0, 0, 0.35}, {0, 0, deg}});
    }
    const KeyframeTrack tr = mustBuild(keys, {LoopMode::Clamp, 1.0, 1.0});
    double turned = 0, prevYaw = 0, minRate = 1e9;
    const int n = 2000;
    for (int i = 0; i <= n; ++i) {
      const double t = tr.endTime() * i / n;
      const KinematicState s = tr.evaluate(t);
      const Vector3d f = s.q * Vector3d::UnitX();
      const double yaw = std::atan2(f.y(), f.x());
      if (i > 0) turned += std::remainder(yaw - prevYaw, 2 * kPi);
      prevYaw = yaw;
      minRate = std::min(minRate, s.w.z());
      EXPECT_LE(std::abs(s.w.x()) + std::abs(s.w.y()), 1e-9);
    }
    EXPECT_NEAR(turned, 4 * kPi, 1e-6) << "step " << step;
    EXPECT_GE(minRate, -1e-9) << "the spin reverses (step " << step << " deg)";
    for (const Keyframe& k : keys) {
      EXPECT_LE(tr.evaluate(k.t).q.angularDistance(eulerDegToQuat(k.rotation)), 1e-9) << k.t;
    }
  }
  // A spin about a tilted axis, keyed as quaternion samples every 120 deg.
  const Vector3d axis = Vector3d(0.3, -0.5, 1.0).normalized();
  std::vector<PoseSample> samples;
  for (int i = 0; i <= 6; ++i)
    samples.push_back({0.3 * i, Vector3d::Zero(), Quaterniond(Eigen::AngleAxisd(i * 2 * kPi / 3, axis))});
  KeyframeTrack tr;
  const Status s = KeyframeTrack::fromSamples(samples, {LoopMode::Clamp, 1.0, 1.0}, tr);
  ASSERT_TRUE(s.ok()) << s.message();
  for (int i = 1; i < 180; ++i) EXPECT_GT(tr.evaluate(1.8 * i / 180).w.dot(axis), 0.0) << i;
}

TEST(Keyframes, SpeedScalesTime) {
  const auto keys = busyKeys();
  const KeyframeTrack slow = mustBuild(keys, {LoopMode::Loop, 1.0, 1.0});
  const KeyframeTrack fast = mustBuild(keys, {LoopMode::Loop, 2.5, 1.0});
  for (double t : {0.1, 0.77, 1.9, 4.0}) {
    const KinematicState a = slow.evaluate(t), b = fast.evaluate(t / 2.5);
    expectNear3(b.x, a.x, 1e-12, "x", t);
    expectNear3(b.v, 2.5 * a.v, 1e-10, "v", t);
    expectNear3(b.a, 6.25 * a.a, 1e-9, "a", t);
    expectNear3(b.w, 2.5 * a.w, 1e-10, "w", t);
    expectNear3(b.alpha, 6.25 * a.alpha, 1e-9, "alpha", t);
  }
}

TEST(Keyframes, BadInputsAreRejectedWithTheKeyAndField) {
  auto expectError = [](const std::vector<Keyframe>& keys, TrackOptions opt, std::vector<std::string> words) {
    KeyframeTrack tr;
    const Status s = KeyframeTrack::fromKeyframes(keys, opt, tr);
    EXPECT_FALSE(s.ok());
    for (const auto& w : words)
      EXPECT_NE(s.message().find(w), std::string::npos) << "'" << w << "' not in: " << s.message();
  };
  const TrackOptions ok{LoopMode::Clamp, 1.0, 1.0};
  expectError({}, ok, {"at least one key"});
  auto keys = busyKeys();
  keys[3].t = keys[2].t;
  expectError(keys, ok, {"key 3", "\"t\"", "increasing"});
  keys = busyKeys();
  keys[4].t = 0.1;
  expectError(keys, ok, {"key 4", "\"t\""});
  keys = busyKeys();
  keys[1].position.y() = std::nan("");
  expectError(keys, ok, {"key 1", "\"position\""});
  keys = busyKeys();
  keys[2].rotation.z() = INFINITY;
  expectError(keys, ok, {"key 2", "\"rotation\""});
  keys = busyKeys();
  keys[5].t = NAN;
  expectError(keys, ok, {"key 5", "\"t\""});
  expectError(busyKeys(), {LoopMode::Clamp, 0.0, 1.0}, {"speed"});
  expectError(busyKeys(), {LoopMode::Clamp, 1.0, -1.0}, {"amplitude"});
  // A loop whose keys make a net full turn cannot close seamlessly.
  expectError({{0, {0, 0, 0}, {0, 0, 0}},
               {1, {0, 0, 0}, {0, 0, 120}},
               {2, {0, 0, 0}, {0, 0, 240}},
               {3, {0, 0, 0}, {0, 0, 360}}},
              {LoopMode::Loop, 1.0, 1.0}, {"loop", "net 360 deg"});
  // Quaternion samples: zero quaternion.
  KeyframeTrack tr;
  std::vector<PoseSample> s{{0, Vector3d::Zero(), Quaterniond::Identity()},
                            {1, Vector3d::Zero(), Quaterniond(0, 0, 0, 0)}};
  const Status zero = KeyframeTrack::fromSamples(s, ok, tr);
  EXPECT_FALSE(zero.ok());
  EXPECT_NE(zero.message().find("key 1"), std::string::npos) << zero.message();
  // The same spin keys are fine in clamp mode.
  EXPECT_TRUE(KeyframeTrack::fromKeyframes({{0, {0, 0, 0}, {0, 0, 0}},
                                            {1, {0, 0, 0}, {0, 0, 120}},
                                            {2, {0, 0, 0}, {0, 0, 240}},
                                            {3, {0, 0, 0}, {0, 0, 360}}},
                                           ok, tr)
                  .ok());
}

TEST(Keyframes, MakeMotionPlaysTheTrack) {
  AnimationParams p;
  p.keys = busyKeys();
  p.speed = 1.5;
  KinematicMotion motion;
  const Status s = makeMotion(p.keys, trackOptions(p), motion);
  ASSERT_TRUE(s.ok()) << s.message();
  const KeyframeTrack tr = mustBuild(p.keys, trackOptions(p));
  expectNear3(motion(0.9).x, tr.evaluate(0.9).x, 1e-15, "x", 0.9);
  EXPECT_FALSE(makeMotion({}, trackOptions(p), motion).ok());
}

// The shipped clips: valid, looping seamlessly (first key = last key), lively but plausible
// (bounded speeds and accelerations), the showcase around the head's rest height.
TEST(Keyframes, ShippedClipsAreValidAndPlausible) {
  const std::vector<std::string> names{"nod", "shake", "turn_and_look", "jump", "whip", "showcase", "toss", "snap"};
  for (const std::string& name : names) {
    const std::string path = "assets/animations/" + name + ".json";
    std::ifstream f(path);
    ASSERT_TRUE(f.good()) << path;
    const nlohmann::json j = nlohmann::json::parse(f);
    AnimationParams p;
    ASSERT_TRUE(enumFromName(j.at("mode").get<std::string>(), p.mode)) << path;
    for (const auto& k : j.at("keys")) {
      Keyframe kf;
      kf.t = k.at("t").get<double>();
      for (int i = 0; i < 3; ++i) kf.position[i] = k.at("position").at(i).get<double>();
      for (int i = 0; i < 3; ++i) kf.rotation[i] = k.at("rotation").at(i).get<double>();
      p.keys.push_back(kf);
    }
    ASSERT_GE(p.keys.size(), 3u) << path;
    EXPECT_EQ(p.mode, LoopMode::Loop) << path;
    EXPECT_LE((p.keys.front().position - p.keys.back().position).norm(), 1e-12) << path << ": first != last key";
    EXPECT_LE((p.keys.front().rotation - p.keys.back().rotation).norm(), 1e-12) << path << ": first != last key";
    KeyframeTrack tr;
    const Status built = KeyframeTrack::fromKeyframes(p.keys, trackOptions(p), tr);
    ASSERT_TRUE(built.ok()) << path << ": " << built.message();
    double vmax = 0, amax = 0, wmax = 0, alphamax = 0, zmin = 1e9, zmax = -1e9;
    for (int i = 0; i <= 4000; ++i) {
      const KinematicState s = tr.evaluate(tr.period() * i / 4000);
      vmax = std::max(vmax, s.v.norm());
      amax = std::max(amax, s.a.norm());
      wmax = std::max(wmax, s.w.norm());
      alphamax = std::max(alphamax, s.alpha.norm());
      zmin = std::min(zmin, s.x.z());
      zmax = std::max(zmax, s.x.z());
    }
    std::printf("[ %s ] period %.2f s, peak |v| %.2f m/s, |a| %.1f m/s^2, |w| %.1f rad/s, |alpha| %.0f rad/s^2\n",
                name.c_str(), tr.period(), vmax, amax, wmax, alphamax);
    // snap is the head collider's stress clip (docs/PHYSICS.md, "No pass-through"): it turns at
    // more than 4x the toss's peak on purpose, beyond what a head plausibly does.
    const bool stress = name == "snap";
    EXPECT_LT(vmax, 4.0) << path;                   // m/s
    EXPECT_LT(amax, 60.0) << path;                  // m/s^2 (a jump's push-off; about 6 g)
    EXPECT_LT(wmax, stress ? 50.0 : 25.0) << path;  // rad/s (a fast whip is ~15-20 rad/s)
    EXPECT_LT(alphamax, 600.0) << path;             // rad/s^2
    EXPECT_GT(wmax + vmax, 0.5) << path;            // it moves
    EXPECT_GT(zmin, 0.15) << path;                  // the head stays around its rest height 0.35 m
    EXPECT_LT(zmax, 0.8) << path;
    if (name == "showcase") {
      EXPECT_GE(tr.period(), 8.0);
      EXPECT_LE(tr.period(), 14.0);
    }
  }
}

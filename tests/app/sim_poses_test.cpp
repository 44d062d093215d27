// `ponyhop sim --poses`: every body's pose and velocity, at every step or at requested times.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "app/pose_sampling.h"
#include "common/run_util.h"
#include "engine/asset_loader.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

using testing::readFile;
using testing::runPonyhop;
using testing::scratch;

struct Row {
  double t = 0;
  int body = 0;
  std::string name;
  double v[13] = {};
};

std::vector<Row> readPoses(const std::string& path, std::string* header) {
  std::istringstream in(readFile(path));
  std::string line;
  std::getline(in, *header);
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string cell;
    Row r;
    std::getline(ls, cell, ',');
    r.t = std::stod(cell);
    std::getline(ls, cell, ',');
    r.body = std::stoi(cell);
    std::getline(ls, r.name, ',');
    for (double& x : r.v) {
      std::getline(ls, cell, ',');
      x = std::stod(cell);
    }
    rows.push_back(r);
  }
  return rows;
}

// Every row against the World's own state, step by step: the hopper with its ponytail (every
// body: the hopper's three and each link) and the head scene (a kinematic head and the links).
void expectRowsMatchWorld(const std::string& scene_path, double duration, int expected_bodies) {
  const std::string dir = scratch("sim_poses");
  const std::string csv = dir + "/poses.csv";
  const auto r =
      runPonyhop("sim " + scene_path + " --duration " + std::to_string(duration) + " --poses " + csv, "sim_poses");
  ASSERT_EQ(r.code, 0) << r.out;
  std::string header;
  const std::vector<Row> rows = readPoses(csv, &header);
  EXPECT_EQ(header, "t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz");

  Sim sim(loadScene(scene_path), &assimpAssets());
  const int n = sim.world().bodyCount();
  ASSERT_EQ(n, expected_bodies);
  const long steps = std::lround(duration / sim.scene().physics.dt);
  ASSERT_EQ(rows.size(), size_t((steps + 1) * n));
  const std::vector<std::string> ids = bodyIds(sim.world());
  for (long k = 0; k <= steps; ++k) {
    if (k > 0) {
      ASSERT_TRUE(sim.step());
    }
    for (int i = 0; i < n; ++i) {
      const Row& row = rows[size_t(k * n + i)];
      const RigidBody& b = sim.world().body(i);
      ASSERT_EQ(row.body, i);
      ASSERT_EQ(row.name, ids[size_t(i)]);
      ASSERT_NEAR(row.t, sim.time(), 1e-9);
      const double want[13] = {b.x.x(), b.x.y(), b.x.z(), b.q.w(), b.q.x(), b.q.y(), b.q.z(),
                               b.v.x(), b.v.y(), b.v.z(), b.w.x(), b.w.y(), b.w.z()};
      for (int c = 0; c < 13; ++c)
        ASSERT_NEAR(row.v[c], want[c], 1e-9 * (1.0 + std::abs(want[c])))
            << "step " << k << " body " << i << " column " << c;
    }
  }
}

TEST(SimPoses, EveryBodyOfTheHopperWithItsPonytailAtEveryStep) {
  // 3 hopper bodies + the links of ponytail_hopper.json.
  const Scene s = loadScene("assets/scenes/ponytail_hopper.json");
  expectRowsMatchWorld("assets/scenes/ponytail_hopper.json", 0.05, 3 + s.chain->links);
}

TEST(SimPoses, HeadAndLinksAtEveryStep) {
  const Scene s = loadScene("assets/scenes/ponytail.json");
  expectRowsMatchWorld("assets/scenes/ponytail.json", 0.1, 1 + s.chain->links);
}

TEST(SimPoses, RequestedTimesAreRowsAtThoseTimes) {
  const std::string dir = scratch("sim_poses_at");
  const auto r =
      runPonyhop("sim assets/scenes/chain.json --poses " + dir + "/p.csv --at 0,0.01,0.0125,0.3", "sim_poses_at");
  ASSERT_EQ(r.code, 0) << r.out;
  std::string header;
  const std::vector<Row> rows = readPoses(dir + "/p.csv", &header);
  const Scene s = loadScene("assets/scenes/chain.json");
  const int n = 1 + s.chain->links;  // the anchor and the links
  ASSERT_EQ(rows.size(), size_t(4 * n));
  EXPECT_DOUBLE_EQ(rows[size_t(2 * n)].t, 0.0125);
  EXPECT_DOUBLE_EQ(rows[size_t(3 * n)].t, 0.3);
  // --rate gives k / rate; a bad --at is refused.
  const auto rate =
      runPonyhop("sim assets/scenes/chain.json --duration 0.5 --poses " + dir + "/q.csv --rate 100", "sim_poses_rate");
  ASSERT_EQ(rate.code, 0) << rate.out;
  EXPECT_EQ(readPoses(dir + "/q.csv", &header).size(), size_t(51 * n));
  const auto bad = runPonyhop("sim assets/scenes/chain.json --poses " + dir + "/b.csv --at 0.2,0.1", "sim_poses_bad");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--at"), std::string::npos) << bad.out;
}

double poseDistance(const PoseFrame& a, const PoseFrame& b) {
  double e = 0.0;
  for (size_t i = 0; i < a.bodies.size(); ++i) e = std::max(e, (a.bodies[i].x - b.bodies[i].x).norm());
  return e;
}

// Between steps, a pose is interpolated to fourth order (cubic Hermite), not held: a swinging
// chain at h = 1/120 and 1/240 s against the same chain at 1/1920 s (whose steps include every
// midpoint). Cubic Hermite is fourth order for a smooth motion; here (position projection after
// each step) halving h divides the midpoint error by about 8 (measured 8.3); a held value is off by
// v h / 2, a thousand times more.
struct MidpointErrors {
  double step = 0.0, mid = 0.0, held = 0.0;
};

std::string exact(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

MidpointErrors midpointErrors(double h) {
  const std::vector<Override> coarse_o{{"physics.dt", exact(h)}, {"chain.links", "3"}};
  const std::vector<Override> fine_o{{"physics.dt", exact(1.0 / 1920.0)}, {"chain.links", "3"}};
  Sim coarse(loadScene("assets/scenes/chain.json", coarse_o), &assimpAssets());
  Sim fine(loadScene("assets/scenes/chain.json", fine_o), &assimpAssets());
  PoseSampler cs(coarse), fs(fine);
  MidpointErrors e;
  PoseFrame c, f, held;
  for (int k = 0; k < int(0.4 / h); ++k) {
    EXPECT_TRUE(cs.at(k * h, c));
    EXPECT_TRUE(fs.at(k * h, f));
    e.step = std::max(e.step, poseDistance(c, f));
    held = c;
    EXPECT_TRUE(cs.at((k + 0.5) * h, c));
    EXPECT_TRUE(fs.at((k + 0.5) * h, f));
    e.mid = std::max(e.mid, poseDistance(c, f));
    e.held = std::max(e.held, poseDistance(held, f));
  }
  std::printf(
      "h = 1/%.0f s: max position error against h = 1/1920 s: at steps %.3g m, interpolated midpoints %.3g m, "
      "held %.3g m\n",
      1.0 / h, e.step, e.mid, e.held);
  return e;
}

TEST(SimPoses, InterpolationBetweenStepsIsThirdOrderAtLeast) {
  const MidpointErrors a = midpointErrors(1.0 / 120.0), b = midpointErrors(1.0 / 240.0);
  EXPECT_GT(a.mid / b.mid, 6.0) << "halving the step must divide the error by 8 or more (third order at least)";
  EXPECT_GT(a.held, 100.0 * a.mid);
  EXPECT_GT(b.held, 100.0 * b.mid);
}

}  // namespace
}  // namespace ponyhop

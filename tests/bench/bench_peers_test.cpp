// The peer engines of `ponyhop bench` (bench/peer.h) build the same chain as ponyhop: at t = 0
// every peer's links sit where ponyhop's are (the tip and the potential energy agree), and after
// 0.1 s of the released 8-link chain at dt = 1/1920 s the tip is where ponyhop's reduced RK4 puts
// it, within what a first-order step can reach. The modules are the ones built beside the
// executable; engines whose module was not built are skipped (the bench then has no rows for
// them), and a module that was built must load.
#include "bench/bench_peers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

std::vector<Override> chainOverrides(const std::string& solver, const std::string& anchor = "fixed") {
  return {{"chain.links", "8"},
          {"anchor.motion", anchor},
          {"physics.solver", solver},
          {"physics.integrator", "rk4"},
          {"physics.stabilization", "none"},
          {"physics.dt", "0.000520833333333333"},
          {"physics.max_step_rotation", "0"}};
}

TEST(BenchPeers, EveryPeerBuildsTheSameChainAndMovesLikeIt) {
  const PeerModules modules = loadPeerModules({std::filesystem::path(PONYHOP_EXE).parent_path().string()});
  for (const std::string& note : modules.notes) {
    EXPECT_EQ(note.find("failed to load"), std::string::npos) << note;
    EXPECT_EQ(note.find(" has no "), std::string::npos) << note;
    std::printf("%s\n", note.c_str());
  }
  const std::vector<Peer>& peers = modules.peers;
  if (peers.empty()) GTEST_SKIP() << "no peer engine's module was built";
  Sim sim(loadScene("assets/scenes/chain.json", chainOverrides("featherstone")));
  ASSERT_TRUE(sim.ok()) << sim.status();
  const PeerChain chain = peerChainOf(sim);
  const Chain& ch = *sim.chain();
  const Eigen::Vector3d tip0 = ch.tip(sim.world());
  double potential0 = 0.0;
  std::vector<Eigen::Vector3d> x0;
  for (int id : ch.links) {
    potential0 -= sim.world().body(id).mass * chain.gravity.dot(sim.world().body(id).x);
    x0.push_back(sim.world().body(id).x);
  }
  const double dt = 1.0 / 1920.0;
  const int steps = 192;  // 0.1 s
  for (int i = 0; i < steps; ++i) ASSERT_TRUE(sim.step()) << sim.status();
  const Eigen::Vector3d tip1 = ch.tip(sim.world());
  ASSERT_GT((tip1 - tip0).norm(), 0.01) << "the chain did not move: the comparison would say nothing";
  for (const Peer& peer : peers) {
    SCOPED_TRACE(peer.name);
    std::string error;
    auto peer_sim = peer.make(chain, dt, error);
    ASSERT_TRUE(peer_sim) << error;
    EXPECT_LT((peer_sim->tip() - tip0).norm(), 1e-9);
    std::vector<PeerLink> links;
    peer_sim->links(links);
    ASSERT_EQ(links.size(), ch.links.size());
    for (size_t i = 0; i < links.size(); ++i) EXPECT_LT((links[i].x - x0[i]).norm(), 1e-9) << "link " << i;
    if (peer.name.rfind("mujoco", 0) != 0) {  // MuJoCo reports its own energy (its reference)
      EXPECT_NEAR(peer_sim->energy(), potential0, 1e-9 * (1.0 + std::abs(potential0)));
    }
    for (int i = 0; i < steps; ++i) peer_sim->step();
    ASSERT_TRUE(peer_sim->finite());
    const double off = (peer_sim->tip() - tip1).norm();
    std::printf("%-16s tip after 0.1 s: %.3g m from ponyhop featherstone/rk4\n", peer.name.c_str(), off);
    // First-order steps at 1/1920 s over 0.1 s of the falling chain: millimetres, not a wrong chain
    // (a swapped inertia or pivot puts the tip centimetres off).
    EXPECT_LT(off, 5e-3);
  }
}

// The bench's shaken case in every peer: the 8-link chain hanging from the shaking anchor
// (physics/models/anchor_motion.h), which at t = 0 is already moving (0.94 m/s in x and z) and
// gives the chain at rest Kelvin's velocities. Each peer takes them (its links' velocities at t = 0
// are ours to 1e-9), moves its anchor along the path (every joint, link 0's to the anchor where the
// path has it at that time, stays closed), and after 0.1 s at 1/1920 s its tip is where ponyhop's
// reduced RK4 puts it: MuJoCo RK4, driven at every stage's time, to round-off; the first-order
// steppers within what they reach on the fixed anchor. A peer whose anchor were carried without
// its acceleration (a mocap body; a moved fixed base) misses by centimetres.
TEST(BenchPeers, EveryPeerShakesTheSameChainLikeIt) {
  const PeerModules modules = loadPeerModules({std::filesystem::path(PONYHOP_EXE).parent_path().string()});
  if (modules.peers.empty()) GTEST_SKIP() << "no peer engine's module was built";
  Sim sim(loadScene("assets/scenes/chain.json", chainOverrides("featherstone", "shake")));
  ASSERT_TRUE(sim.ok()) << sim.status();
  const PeerChain chain = peerChainOf(sim);
  ASSERT_TRUE(chain.moving());
  ASSERT_GT(chain.anchorAt(0.0).v.norm(), 0.5) << "the anchor does not move at t = 0: the start says nothing";
  const Chain& ch = *sim.chain();
  std::vector<Eigen::Vector3d> x0, v0, w0;
  for (int id : ch.links) {
    x0.push_back(sim.world().body(id).x);
    v0.push_back(sim.world().body(id).v);
    w0.push_back(sim.world().body(id).w);
  }
  ASSERT_GT(w0[0].norm(), 0.1) << "the chain took no Kelvin velocities: the start says nothing";
  const double dt = 1.0 / 1920.0;
  const int steps = 192;  // 0.1 s
  for (int i = 0; i < steps; ++i) ASSERT_TRUE(sim.step()) << sim.status();
  const Eigen::Vector3d tip1 = ch.tip(sim.world());
  for (const Peer& peer : modules.peers) {
    SCOPED_TRACE(peer.name);
    std::string error;
    auto peer_sim = peer.make(chain, dt, error);
    ASSERT_TRUE(peer_sim) << error;
    std::vector<PeerLink> links;
    peer_sim->links(links);
    ASSERT_EQ(links.size(), ch.links.size());
    for (size_t i = 0; i < links.size(); ++i) {
      EXPECT_LT((links[i].x - x0[i]).norm(), 1e-9) << "link " << i;
      EXPECT_LT((links[i].v - v0[i]).norm(), 1e-9) << "link " << i;
      EXPECT_LT((links[i].w - w0[i]).norm(), 1e-9) << "link " << i;
    }
    double open = 0.0;
    for (int i = 0; i < steps; ++i) {
      peer_sim->step();
      peer_sim->links(links);
      open = std::max(open, peerJointError(chain, links, peer_sim->time()));
    }
    ASSERT_TRUE(peer_sim->finite());
    const double off = (peer_sim->tip() - tip1).norm();
    std::printf("%-16s shaken: tip after 0.1 s %.3g m from ponyhop featherstone/rk4, joints (anchor too) open %.3g m\n",
                peer.name.c_str(), off, open);
    EXPECT_LT(off, peer.name == "mujoco/RK4" ? 1e-9 : 5e-3);
    // Reduced coordinates: the anchor's joint is the only one that can open (it moves as driven);
    // ODE pulls its joints back by 20 % a step.
    EXPECT_LT(open, peer.name.rfind("ode/", 0) == 0 ? 1e-4 : 1e-9);
  }
}

// The four-bar (bench/peer.h, PeerFourBar) in every peer: at t = 0 its links sit where ours are and
// its joints (the closure too) are closed; after 0.1 s with the servo on (ours at its own dt, the
// peers at 1/1920 s) the crank has turned as ours has and the loop has stayed closed to what the
// engine's constraint allows (a wrong pivot, axis or closure point shows as centimetres).
TEST(BenchPeers, EveryPeerBuildsTheSameFourBarAndDrivesItLikeIt) {
  const PeerModules modules = loadPeerModules({std::filesystem::path(PONYHOP_EXE).parent_path().string()});
  if (modules.peers.empty()) GTEST_SKIP() << "no peer engine's module was built";
  Sim sim(loadScene("assets/scenes/four_bar.json", {{"physics.dt", "0.000520833333333333"}}));
  ASSERT_TRUE(sim.ok()) << sim.status();
  const PeerFourBar four_bar = peerFourBarOf(sim);
  const Chain& ch = *sim.chain();
  std::vector<Eigen::Vector3d> x0;
  for (int id : ch.links) x0.push_back(sim.world().body(id).x);
  const int steps = 192;  // 0.1 s at 1/1920 s
  for (int i = 0; i < steps; ++i) ASSERT_TRUE(sim.step()) << sim.status();
  std::vector<Eigen::Vector3d> x1;
  for (int id : ch.links) x1.push_back(sim.world().body(id).x);
  ASSERT_GT((x1[1] - x0[1]).norm(), 0.01) << "the coupler did not move: the comparison would say nothing";
  for (const Peer& peer : modules.peers) {
    SCOPED_TRACE(peer.name);
    ASSERT_TRUE(peer.makeFourBar);
    std::string error;
    auto peer_sim = peer.makeFourBar(four_bar, 1.0 / 1920.0, error);
    ASSERT_TRUE(peer_sim) << error;
    std::vector<PeerLink> links;
    peer_sim->links(links);
    ASSERT_EQ(links.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_LT((links[i].x - x0[i]).norm(), 1e-9) << "link " << i;
      EXPECT_LT(links[i].q.angularDistance(four_bar.chain.q[i]), 1e-9) << "link " << i;
    }
    EXPECT_LT(four_bar.jointError(links), 1e-9);
    double closure = 0.0;
    for (int i = 0; i < steps; ++i) {
      peer_sim->step();
      peer_sim->links(links);
      closure = std::max(closure, four_bar.jointError(links));
    }
    ASSERT_TRUE(peer_sim->finite());
    double off = 0.0;
    for (size_t i = 0; i < 3; ++i) off = std::max(off, (links[i].x - x1[i]).norm());
    std::printf("%-16s four-bar after 0.1 s: links %.3g m from ours, joints open %.3g m at most\n", peer.name.c_str(),
                off, closure);
    EXPECT_LT(off, 5e-3);
    EXPECT_LT(closure, 5e-3);
  }
}

}  // namespace
}  // namespace ponyhop

// The peer engines of `ponyhop bench` as the bench drives them (bench/peer.h: the chain, the
// engines' interface): the chain read from a built scene, the modules found and loaded, and a
// peer's run measured like one of ours.
#pragma once

#include <string>
#include <vector>

#include "bench/bench_run.h"
#include "bench/peer.h"
#include "sim/sim.h"

namespace ponyhop {

// The chain of a built scene (its chain, its anchor fixed or moving, the links' velocities at
// t = 0) as the peers build it.
PeerChain peerChainOf(const Sim& sim);

// The four-bar of a built scene (assets/scenes/four_bar.json: a three-link chain on a root hinge,
// its last link's bottom end hinged to the world about the same axis) as the peers build it;
// throws when the scene is not such a four-bar.
PeerFourBar peerFourBarOf(const Sim& sim);

// The peers of the modules that loaded, and one note per engine: its version and settings, or
// that its module was not built or failed to load (and why).
struct PeerModules {
  std::vector<Peer> peers;
  std::vector<std::string> notes;
};

// Loads ponyhop-peer-<engine>.so of each engine from the first folder of `dirs` that has it.
// A module stays loaded for the life of the process (its peers' code is in it).
PeerModules loadPeerModules(const std::vector<std::string>& dirs);

// Where the executable looks for the modules: its own folder (a build folder), then the install
// layout's PREFIX/LIBDIR/ponyhop (found relative to the executable, as its assets are).
std::vector<std::string> peerModuleDirs();

// One peer run, measured like benchRun(): `repeats` timed runs of [0, horizon], the tip's error
// against the reference, then the first repeat continued (untimed) to long_duration for the
// energy drift (conservative: against the peer's own energy at t = 0; e_start: the chain's energy in
// ponyhop's reference, for the relative drift) or, on a driven chain (the shaking anchor), the joint
// drift: bounded as ours are (joints within 1 cm, the tip slower than 100 m/s).
RunResult benchPeerRun(const Peer& peer, const PeerChain& chain, double dt, double horizon, int repeats,
                       double long_duration, const Trajectory& reference, double e_start, bool conservative = true);

// The build flags of ours (this build's compiler, build type and flags) and of each engine's
// Debian package as far as it records them (its version, its pkg-config flags; Debian's default
// compiler flags), one line each.
std::vector<std::string> buildFlagNotes();

// The peer as a configuration of the scaling sweep (bench_run.h): the chain of `scene` with
// scalingOverrides(N), stepped at kBenchGrid; its joint error from the links' ends.
ScalingConfig peerScalingConfig(const Peer& peer, const std::string& scene);

// The largest gap of a joint of `links` (link i's top end against link i-1's bottom end, link 0's
// against the anchor where it is at time t), m.
double peerJointError(const PeerChain& chain, const std::vector<PeerLink>& links, double t = 0.0);

}  // namespace ponyhop

// The panel's artist scales (app/chain_look.h) map to the physical fields and back exactly, the
// root-to-tip curves keep uniform chains bit-identical, and the shipped presets load, apply from
// the command line and the panel, and round-trip through a saved scene file.
#include "app/chain_look.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "app/presets.h"
#include "common/run_util.h"
#include "common/sanitizers.h"
#include "engine/asset_loader.h"
#include "physics/models/chain.h"
#include "sim/scene_io.h"
#include "sim/sim.h"

namespace ponyhop {
namespace {

// Exact up to rounding: 1e-12 relative; damping through bounce = 1 - damping ratio loses digits
// when the ratio is small (1 - 0.999...), so it gets 1e-9.
bool near(double a, double b, double rel = 1e-12) {
  return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b)) + 1e-300;
}

std::vector<ChainParams> chains() {
  std::vector<ChainParams> out;
  for (int links : {1, 2, 8, 33}) {
    for (double taper : {1.0, 0.35}) {
      ChainParams p;
      p.links = links;
      p.taper = taper;
      p.length = 0.028;
      p.mass = 0.012;
      p.radius = 0.014;
      p.stiffness = 3e-4;
      p.damping = 1e-5;
      p.drag = 0.02;
      out.push_back(p);
    }
  }
  return out;
}

TEST(ChainLook, PhysicalToArtistAndBackIsExact) {
  const double g = 9.81;
  for (ChainParams p : chains()) {
    const ChainParams original = p;
    const ChainLook l = chainLook(p, g);
    setLength(p, l.length_cm);
    setThickness(p, l.thickness_mm);
    setWeight(p, l.weight_g);
    setStiffness(p, l.stiffness, g);
    setBounce(p, l.bounce, g);
    setAir(p, l.air);
    EXPECT_TRUE(near(p.length, original.length)) << p.links;
    EXPECT_TRUE(near(p.radius, original.radius));
    EXPECT_TRUE(near(p.mass, original.mass));
    EXPECT_TRUE(near(p.stiffness, original.stiffness)) << p.stiffness << " " << original.stiffness;
    EXPECT_TRUE(near(p.damping, original.damping, 1e-9)) << p.damping << " " << original.damping;
    EXPECT_TRUE(near(p.drag, original.drag)) << p.drag << " " << original.drag;
  }
}

TEST(ChainLook, ArtistToPhysicalAndBackIsExact) {
  const double g = 9.81;
  for (ChainParams p : chains()) {
    setLength(p, 37.5);
    setThickness(p, 21.0);
    setWeight(p, 55.0);
    setStiffness(p, 0.4, g);
    setBounce(p, 0.85, g);
    setAir(p, 0.3);
    const ChainLook l = chainLook(p, g);
    EXPECT_TRUE(near(l.length_cm, 37.5)) << l.length_cm;
    EXPECT_TRUE(near(l.thickness_mm, 21.0));
    EXPECT_TRUE(near(l.weight_g, 55.0)) << l.weight_g;
    EXPECT_TRUE(near(l.stiffness, 0.4)) << l.stiffness;
    EXPECT_TRUE(near(l.bounce, 0.85)) << l.bounce;
    EXPECT_TRUE(near(l.air, 0.3)) << l.air;
  }
}

TEST(ChainLook, ScalesMeanWhatTheySay) {
  ChainParams p;  // 8 cylinders of 5 cm, 20 g each
  p.links = 8;
  const double g = 9.81;
  EXPECT_DOUBLE_EQ(chainLook(p, g).length_cm, 40.0);
  EXPECT_DOUBLE_EQ(chainLook(p, g).weight_g, 160.0);
  EXPECT_DOUBLE_EQ(chainLook(p, g).thickness_mm, 20.0);
  // Stiffness 1: the root spring equals the gravity torque per radian of the chain held out
  // straight, M g d with d = 20 cm (the centre of 8 x 5 cm).
  setStiffness(p, 1.0, g);
  EXPECT_NEAR(p.stiffness, 0.16 * g * 0.2, 1e-12);
  // Bounce 0: the root swing is critically damped; its period without damping: 2 pi sqrt(I / k).
  setBounce(p, 0.0, g);
  EXPECT_NEAR(p.damping, criticalDamping(p, g), 1e-15);
  EXPECT_GT(swingPeriod(p, g), 0.3);
  EXPECT_LT(swingPeriod(p, g), 2.0);
  // Air 0.5: drag halves the speed of a freely moving ponytail in one second: exp(-c L / M) = 1/2.
  setAir(p, 0.5);
  EXPECT_NEAR(std::exp(-p.drag * 0.4 / 0.16), 0.5, 1e-12);
}

TEST(ChainCurves, TipRatiosShapeTheJointsAndOneKeepsThemUniform) {
  ChainParams p;
  p.links = 5;
  p.stiffness = 0.01;
  p.damping = 1e-4;
  EXPECT_EQ(jointStiffness(p, 4), p.stiffness) << "ratio 1: exactly the root value";
  p.stiffness_tip = 0.01;
  p.damping_tip = 4.0;
  EXPECT_DOUBLE_EQ(jointStiffness(p, 0), 0.01);
  EXPECT_NEAR(jointStiffness(p, 2), 0.001, 1e-15) << "geometric: the middle joint at sqrt(ratio)";
  EXPECT_NEAR(jointStiffness(p, 4), 0.0001, 1e-16);
  EXPECT_NEAR(jointDamping(p, 4), 4e-4, 1e-17);
  // The world gets those values: the curved chain moves differently from the uniform one.
  auto tipDrop = [](ChainParams q) {
    PhysicsParams pp;
    pp.dt = 1.0 / 1000.0;
    World w{pp};
    const int anchor = w.addKinematicBody([](double) { return KinematicState{}; }, "anchor");
    Chain c = addChain(w, q, anchor, Eigen::Vector3d::Zero());
    double mean_z = 0.0;  // over 2 s: the swing averages out, the sag stays
    for (int i = 0; i < 2000; ++i) {
      w.step();
      mean_z += c.tip(w).z() / 2000.0;
    }
    EXPECT_TRUE(w.ok()) << w.status();
    return mean_z;
  };
  ChainParams uniform = p;
  uniform.stiffness_tip = 1.0;
  uniform.direction = p.direction = Eigen::Vector3d(1, 0, 0);
  EXPECT_GT(std::abs(tipDrop(p) - tipDrop(uniform)), 1e-3) << "the tip ratios reach the joints";
}

TEST(Presets, ShippedPresetsLoadAndChangeTheLook) {
  const std::vector<std::string> names = presetNames();
  for (const char* n : {"silky", "thick", "wet", "stiff", "bouncy"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  }
  const Scene base = loadScene("assets/scenes/ponytail.json");
  for (const std::string& n : names) {
    const Scene s = applyPreset(base, n);
    EXPECT_EQ(s.path, base.path);
    EXPECT_NE(sceneToJson(s)["chain"], sceneToJson(base)["chain"]) << n << " changes the ponytail";
    EXPECT_EQ(sceneToJson(s)["physics"], sceneToJson(base)["physics"]) << n << " leaves the rest alone";
    EXPECT_EQ(s.chain->links, base.chain->links);
    Sim sim(s, &assimpAssets());
    // 1 s of the scene (0.25 s under the sanitizers: 29 s of the ASan run's time for the 1 s).
    for (int i = 0; i < testing::fullOrSanitized(240, 60) && sim.ok(); ++i) sim.step();
    EXPECT_TRUE(sim.ok()) << n << ": " << sim.status();
  }
  // Different looks: the stiff preset's ponytail is stiffer than the silky one's, the wet one heavier.
  const double g = 9.81;
  EXPECT_GT(chainLook(*applyPreset(base, "stiff").chain, g).stiffness,
            chainLook(*applyPreset(base, "silky").chain, g).stiffness);
  EXPECT_GT(chainLook(*applyPreset(base, "wet").chain, g).weight_g,
            chainLook(*applyPreset(base, "silky").chain, g).weight_g);
  EXPECT_GT(chainLook(*applyPreset(base, "bouncy").chain, g).bounce,
            chainLook(*applyPreset(base, "wet").chain, g).bounce);
}

TEST(Presets, RoundTripThroughASavedSceneAndTheCommandLine) {
  const std::string dir = testing::scratch("presets_rt");
  const Scene s = applyPreset(loadScene("assets/scenes/ponytail.json"), "silky", {parseOverride("chain.taper=0.5")});
  EXPECT_EQ(s.chain->taper, 0.5) << "--set wins over the preset";
  saveScene(s, dir + "/silky_scene.json");
  EXPECT_EQ(sceneToJson(loadScene(dir + "/silky_scene.json")), sceneToJson(s));
  // `ponyhop sim --preset`: the same numbers as the scene with the preset laid over it by hand.
  const auto a = testing::runPonyhop(
      "sim assets/scenes/ponytail.json --preset silky --duration 0.5 --csv " + dir + "/a.csv", "preset_sim_a");
  const auto b = testing::runPonyhop(
      "sim " + dir + "/silky_scene.json --set chain.taper=0.3 --duration 0.5 --csv " + dir + "/b.csv", "preset_sim_b");
  ASSERT_EQ(a.code, 0) << a.out;
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_EQ(testing::readFile(dir + "/a.csv"), testing::readFile(dir + "/b.csv"));
  EXPECT_NE(testing::readFile(dir + "/a.csv"), "");
}

TEST(Presets, BadPresetsAreClearErrors) {
  const Scene chain_scene = loadScene("assets/scenes/ponytail.json");
  try {
    applyPreset(chain_scene, "curly");
    ADD_FAILURE() << "no such preset";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("silky"), std::string::npos) << "lists the shipped ones: " << e.what();
  }
  try {
    applyPreset(loadScene("assets/scenes/hopper.json"), "silky");
    ADD_FAILURE() << "a preset must not add a ponytail";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has no 'chain' section"), std::string::npos) << e.what();
  }
  const std::string dir = testing::scratch("presets_bad");
  testing::writeFile(dir + "/bad.json", "{\"chain\": {\"stiffness\": -1}}");
  try {
    applyPreset(chain_scene, dir + "/bad.json");
    ADD_FAILURE() << "out of range";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("chain.stiffness"), std::string::npos) << e.what();
  }
  const auto r =
      testing::runPonyhop("sim assets/scenes/hopper.json --preset wet --csv " + dir + "/x.csv", "preset_bad_cli");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("no 'chain' section"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace ponyhop

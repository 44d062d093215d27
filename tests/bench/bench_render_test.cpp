// `ponyhop bench-render`, the real executable at a small size: the table it writes has every
// configuration of every scene and size, the ratios follow from the times, and bad input is
// refused before anything is measured.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench/commands.h"
#include "common/run_util.h"

namespace {

using ponyhop::testing::readFile;
using ponyhop::testing::runPonyhop;
using ponyhop::testing::scratch;

std::vector<std::string> cells(const std::string& row) {
  std::vector<std::string> out;
  std::stringstream ss(row);
  std::string c;
  std::getline(ss, c, '|');  // before the first bar
  while (std::getline(ss, c, '|')) {
    const size_t a = c.find_first_not_of(' '), b = c.find_last_not_of(' ');
    out.push_back(a == std::string::npos ? "" : c.substr(a, b - a + 1));
  }
  if (!out.empty() && out.back().empty()) out.pop_back();
  return out;
}

TEST(BenchRender, WritesEveryConfigurationAndItsRatioToTheFloor) {
  const std::string dir = scratch("bench_render");
  const std::string out = dir + "/table.md";
  const auto r = runPonyhop(
      "bench-render --scenes assets/scenes/hopper.json,assets/scenes/chain.json --sizes "
      "96x64,64x48 --frames 2 --out " +
          out,
      "bench_render");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string md = readFile(out);
  EXPECT_NE(md.find("llvmpipe"), std::string::npos) << "the table names the GL renderer\n" << md;
  EXPECT_NE(md.find("load average at the start"), std::string::npos) << md;

  // Per scene and size: the six configurations, times finite and positive, x floor = render /
  // the floor's render, the floor's own ratio 1.
  const std::vector<std::string> configs = {"final (as shipped)",
                                            "samples=1 (no AA)",
                                            "+ light.intensity=0 (no shadow)",
                                            "+ ground=false: **floor**",
                                            "final with 4x MSAA (antialias=msaa)",
                                            "draft (quality=draft)"};
  std::map<std::string, std::map<std::string, std::vector<double>>> tables;  // "## heading" -> config -> cells
  std::map<std::string, double> summary;                                     // "scene size" -> x floor
  std::map<std::string, std::map<std::string, std::string>> maps;            // ... -> config -> shadow map
  std::string section;
  std::stringstream ss(md);
  for (std::string line; std::getline(ss, line);) {
    if (line.rfind("## ", 0) == 0) section = line.substr(3);
    if (line.rfind("| ", 0) != 0 || line.find("---") != std::string::npos) continue;
    const auto c = cells(line);
    if (section == "Final / floor") {
      if (c.size() == 5 && c[0] != "scene") summary[c[0] + " " + c[1]] = std::stod(c[4]);
      continue;
    }
    if (c.size() != 8 || c[0] == "configuration") continue;
    std::vector<double> v;
    for (size_t i = 1; i < 7; ++i) v.push_back(std::stod(c[i]));
    tables[section][c[0]] = v;
    maps[section][c[0]] = c[7];
  }
  const std::vector<std::string> headings = {"assets/scenes/hopper.json at 96x64", "assets/scenes/hopper.json at 64x48",
                                             "assets/scenes/chain.json at 96x64", "assets/scenes/chain.json at 64x48"};
  ASSERT_EQ(tables.size(), headings.size()) << md;
  for (const auto& h : headings) {
    ASSERT_TRUE(tables.count(h)) << h << "\n" << md;
    const auto& t = tables[h];
    ASSERT_EQ(t.size(), configs.size()) << h;
    for (const auto& cfg : configs) {
      ASSERT_TRUE(t.count(cfg)) << h << ": " << cfg;
      for (double x : t.at(cfg)) EXPECT_TRUE(std::isfinite(x) && x >= 0.0) << h << ": " << cfg;
      EXPECT_GT(t.at(cfg)[0], 0.0) << h << ": " << cfg << " took no time";
    }
    // Printed to 0.1 ms and 0.01: the ratio of the printed times may be off by their rounding.
    const double floor_ms = t.at(configs[3])[0], floor_lo = std::max(floor_ms - 0.05, 0.01);
    for (const auto& cfg : configs) {
      const double ms = t.at(cfg)[0];
      EXPECT_NEAR(t.at(cfg)[5], ms / floor_ms, 0.05 / floor_lo + (ms + 0.05) * 0.05 / (floor_lo * floor_lo) + 0.006)
          << h << ": " << cfg;
    }
    EXPECT_DOUBLE_EQ(t.at(configs[3])[5], 1.0) << h;
    // The passes the configurations turn off take no time there.
    EXPECT_EQ(t.at(configs[2])[1], 0.0) << h << ": a shadow pass without a light";
    EXPECT_EQ(t.at(configs[1])[3], 0.0) << h << ": anti-aliasing with 1 sample";
    // The shadow map's side: none without a light; at these tiny sizes the fewest texels the
    // renderer matches to a frame (512), half of it in draft; the chain's hair keeps all 1024.
    const auto& m = maps[h];
    const bool hair = h.find("chain") != std::string::npos;
    EXPECT_EQ(m.at(configs[2]), "-") << h;
    EXPECT_EQ(m.at(configs[3]), "-") << h;
    EXPECT_EQ(m.at(configs[0]), hair ? "1024" : "512") << h;
    EXPECT_EQ(m.at(configs[5]), hair ? "512" : "256") << h;
  }
  // The summary at the top repeats each final / floor.
  ASSERT_EQ(summary.size(), headings.size()) << md;
  EXPECT_DOUBLE_EQ(summary["hopper 96x64"], tables[headings[0]].at(configs[0])[5]);
  EXPECT_DOUBLE_EQ(summary["chain 64x48"], tables[headings[3]].at(configs[0])[5]);
}

TEST(BenchRender, BadInputIsRefusedBeforeAnythingIsMeasured) {
  const std::string dir = scratch("bench_render_bad");
  const std::string out = dir + "/table.md";
  // A bad last size or scene: refused at once, naming it, and no table written.
  auto r = runPonyhop("bench-render --scenes assets/scenes/hopper.json --sizes 96x64,12 --frames 2 --out " + out,
                      "bench_render_bad_size");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--sizes 12"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("WIDTHxHEIGHT"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("bench-render: assets/scenes/hopper.json 96x64"), std::string::npos)
      << "measured before the bad size was seen\n"
      << r.out;
  r = runPonyhop(
      "bench-render --scenes assets/scenes/hopper.json,no_such_scene.json --sizes 96x64 --frames 2 --out " + out,
      "bench_render_bad_scene");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("no_such_scene.json"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("bench-render: assets/scenes/hopper.json 96x64"), std::string::npos)
      << "measured before the bad scene was seen\n"
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
}

// The default scenes are the demo's (the Makefile's DEMO_SCENES, as `make demo` reads it), in its
// order, then ponytail_hopper, and each is a scene file: a scene added to the demo is benched too.
TEST(BenchRender, DefaultScenesAreTheDemosScenes) {
  std::ifstream mk("Makefile");
  ASSERT_TRUE(mk) << "run from the repository root";
  std::vector<std::string> demo;
  for (std::string line; std::getline(mk, line);) {
    if (line.rfind("DEMO_SCENES", 0) != 0 || line.find("?=") == std::string::npos) continue;
    std::istringstream names(line.substr(line.find("?=") + 2));
    for (std::string n; names >> n;) demo.push_back("assets/scenes/" + n + ".json");
  }
  ASSERT_FALSE(demo.empty()) << "the Makefile's DEMO_SCENES ?= line";
  std::vector<std::string> expected = demo;
  expected.push_back("assets/scenes/ponytail_hopper.json");
  const std::vector<std::string> scenes = ponyhop::benchRenderDefaultScenes();
  EXPECT_EQ(scenes, expected);
  for (const std::string& s : scenes) EXPECT_TRUE(std::filesystem::is_regular_file(s)) << s;
}

}  // namespace

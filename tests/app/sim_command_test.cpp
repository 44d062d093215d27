// `ponyhop sim` on the hopper scene: writes the hopper columns and takes the command keys with
// --set.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "common/run_util.h"

namespace ponyhop {
namespace {

using testing::readFile;
using testing::runPonyhop;
using testing::scratch;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

TEST(SimCommand, SimWritesTheHopperColumnsAndTakesCommands) {
  const std::string dir = scratch("hopper_sim");
  const std::string csv = dir + "/hop.csv";
  // The course's script is cleared so that the command alone drives the hopper.
  const auto r = runPonyhop(
      "sim assets/scenes/hopper.json --duration 8 --set hopper.script=[] "
      "--set hopper.command.vx=0.6 --set hopper.command.vy=-0.3 --set hopper.command.height=1.1 "
      "--csv " +
          csv,
      "hopper_sim");
  ASSERT_EQ(r.code, 0) << r.out;
  std::stringstream in(readFile(csv));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t,x,y,z,vx,vy,vz,roll,pitch,yaw,leg_length,phase,foot_x,foot_y,foot_z,contact,knee_error");
  int rows = 0, contact_rows = 0;
  std::set<std::string> phases;
  std::vector<std::string> last;
  double x4 = 0, y4 = 0, max_z = 0;
  while (std::getline(in, line)) {
    const auto c = split(line);
    ASSERT_EQ(c.size(), 17u) << line;
    ++rows;
    phases.insert(c[11]);
    contact_rows += c[15] == "1";
    EXPECT_GT(std::stod(c[14]), -2e-3) << "foot below the ground: " << line;
    EXPECT_LT(std::stod(c[16]), 1e-9) << "knee error: " << line;
    const double t = std::stod(c[0]);
    if (std::abs(t - 4.0) < 1e-9) {
      x4 = std::stod(c[1]);
      y4 = std::stod(c[2]);
    }
    if (t > 4.0) max_z = std::max(max_z, std::stod(c[3]));
    last = c;
  }
  EXPECT_EQ(rows, 8001) << "one row per millisecond";
  EXPECT_EQ(phases, (std::set<std::string>{"flight", "loading", "compression", "thrust", "unloading"}));
  EXPECT_GT(contact_rows, 1000);
  const double vx = (std::stod(last[1]) - x4) / 4.0, vy = (std::stod(last[2]) - y4) / 4.0;
  std::printf("[ sim --set ] mean velocity 4-8 s (%.3f, %.3f) m/s (command (0.6, -0.3)), highest apex %.3f m (1.1)\n",
              vx, vy, max_z);
  EXPECT_NEAR(vx, 0.6, 0.1);
  EXPECT_NEAR(vy, -0.3, 0.1);
  EXPECT_NEAR(max_z, 1.1, 0.03);
}

}  // namespace
}  // namespace ponyhop

// `ponyhop bench --loops-only` (bench/bench_loops.cpp) on a short run: it writes its tables, a row
// that stops (an explicit step past its stability limit at 1/60 s) is written with its reason and
// does not fail the bench, and with projection every solver closes both loops.
#include "bench/bench_loops.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "common/out_util.h"

namespace ponyhop {
namespace {

TEST(BenchLoops, AShortRunClosesEveryLoopAndAStoppedRowIsAFindingNotAFailure) {
  LoopBenchOptions o;
  o.dts = {60, 240};
  o.four_bar_seconds = 0.1;
  o.hair_loop_seconds = 0.1;
  o.agree_dts = {};  // its runs are a second long: the bench checks them
  o.repeats = 1;
  o.peer_dirs = {std::filesystem::path(PONYHOP_EXE).parent_path().string()};  // the peers' modules, when built
  o.out = std::string(PONYHOP_TEST_OUT) + "/bench-loops";
  o.command_line = "bench_loops_test";
  EXPECT_EQ(runLoopBench(o), 0);
  const std::string s = testing::readFile(o.out + "/loops.md");
  EXPECT_NE(s.find("stopped:"), std::string::npos) << "no row stopped at 1/60 s: the exit status is not exercised";
  // Each projection row at 1/240 s, in both tables (the four-bar's, the hair loop's): its closure,
  // the third cell, within the goal of 1e-10 m.
  for (const char* solver : {"dense", "tree", "featherstone"}) {
    const std::string row = std::string("| ") + solver + "/rk4/projection | 1/240 | ";
    int rows = 0;
    for (size_t at = s.find(row); at != std::string::npos; at = s.find(row, at + 1)) {
      const double closure = std::strtod(s.c_str() + at + row.size(), nullptr);
      EXPECT_LE(closure, 1e-10) << row;
      ++rows;
    }
    EXPECT_EQ(rows, 2) << row;
  }
}

}  // namespace
}  // namespace ponyhop

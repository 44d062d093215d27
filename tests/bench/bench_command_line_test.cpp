// The bench's command lines are described without CLI11 (app/commands.h, CommandSpec) and added to
// `ponyhop` by app/commands.cpp: a value outside an option's range or set, in a plain option or in
// one item of a comma list, is a usage error (exit code 2) naming the option, before anything runs.
// (That the lists are split: BenchRender.BadInputIsRefusedBeforeAnythingIsMeasured.)
#include <gtest/gtest.h>

#include <string>

#include "common/run_util.h"

namespace {

using ponyhop::testing::runPonyhop;

struct UsageCase {
  const char* args;
  const char* says;  // CLI11's message for the check that refuses it
};

TEST(BenchCommandLine, ValuesOutsideAnOptionsRangeOrSetAreUsageErrors) {
  const UsageCase cases[] = {
      {"bench-render --frames 0", "--frames: Value 0 not in range 1 to 10000"},           // int range
      {"bench --links 8,0", "--links: Value 0 not in range 1 to 4096"},                   // one item of a list
      {"bench --anchors fixed,foo", "--anchors: foo not in {fixed,shake}"},               // a set
      {"bench --scaling-seconds 0", "--scaling-seconds: Value 0 not in range 0.001000"},  // double range
  };
  for (const UsageCase& c : cases) {
    const auto r = runPonyhop(c.args, "bench_command_line");
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << c.args << "\n" << r.out;
  }
}

}  // namespace

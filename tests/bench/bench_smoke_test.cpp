// Smoke test of `ponyhop bench --quick`: the real executable runs headless and writes its CSV and
// Markdown; every number in them is finite, or its row says it failed and why.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_report.h"
#include "common/out_util.h"
#include "common/sanitizers.h"

namespace {

namespace fs = std::filesystem;

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const {
    for (size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) return static_cast<int>(i);
    }
    return -1;
  }
};

Csv readCsv(const fs::path& p) {
  Csv csv;
  std::ifstream f(p);
  std::string line;
  if (std::getline(f, line)) csv.header = ponyhop::splitCsvLine(line);
  while (std::getline(f, line)) {
    if (!line.empty()) csv.rows.push_back(ponyhop::splitCsvLine(line));
  }
  return csv;
}

// A field that is not text: empty (not applicable) or a finite number.
bool finiteOrEmpty(const std::string& s) {
  if (s.empty()) return true;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end && *end == '\0' && std::isfinite(v);
}

bool isNumber(const std::string& s) { return !s.empty() && finiteOrEmpty(s); }

const std::set<std::string> kText{"case",          "anchor",    "method", "solver", "integrator",
                                  "stabilization", "step",      "status", "reason", "long_status",
                                  "long_reason",   "reference", "config", "drift"};

class BenchSmoke : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // ctest runs each TEST in its own process, in parallel. The four read one run of the bench
    // (a minute under ASan): the first process to take the lock runs it into a folder named for
    // this build of the executable, the others wait and read what it wrote. Under the sanitizers
    // the chains run at the first of quick's two steps only (1/120 s, the one the step-control
    // rows are read at; 1/480 s runs the same code for 15 of the 63 s there).
    const fs::path exe(PONYHOP_EXE);
    const auto stamp = fs::last_write_time(exe).time_since_epoch().count();
    out_ = fs::path(PONYHOP_TEST_OUT) /
           ("bench-smoke-" + std::to_string(stamp) + "-" + std::to_string(fs::file_size(exe)));
    fs::create_directories(out_);
    const int lock = ::open((out_ / "lock").c_str(), O_CREAT | O_RDWR, 0644);
    ASSERT_GE(lock, 0);
    ASSERT_EQ(::flock(lock, LOCK_EX), 0);
    const fs::path done = out_ / "exit_status.txt";
    if (std::ifstream in(done); !(in >> rc_)) {
      fs::remove_all(out_ / "run");  // a run that died half way: start again
      const std::string cmd = std::string(PONYHOP_EXE) + " bench --quick --out " + (out_ / "run").string() +
                              (ponyhop::testing::kSanitized ? " --dts 120" : "") + " 2>" +
                              (out_ / "stderr.txt").string();
      rc_ = std::system(cmd.c_str());
      std::ofstream(done) << rc_ << "\n";
    }
    ::close(lock);
    out_ /= "run";
  }
  static fs::path out_;
  static int rc_;
};
fs::path BenchSmoke::out_;
int BenchSmoke::rc_ = -1;

TEST_F(BenchSmoke, RunsAndWritesItsFiles) {
  ASSERT_EQ(rc_, 0) << "see " << (out_.parent_path() / "stderr.txt");
  for (const char* f : {"bench.csv", "reference.csv", "scaling.csv", "README.md"}) {
    EXPECT_TRUE(fs::exists(out_ / f)) << f;
    EXPECT_GT(fs::file_size(out_ / f), 50u) << f;
  }
  const std::string readme = ponyhop::testing::readFile((out_ / "README.md").string());
  EXPECT_NE(readme.find("| method |"), std::string::npos) << "no table in README.md";
  EXPECT_NE(readme.find("ponyhop bench --quick"), std::string::npos) << "README.md does not name its command";
}

TEST_F(BenchSmoke, EveryNumberIsFiniteOrTheRowSaysWhyItFailed) {
  ASSERT_EQ(rc_, 0);
  const Csv csv = readCsv(out_ / "bench.csv");
  ASSERT_FALSE(csv.rows.empty());
  const int status = csv.column("status"), reason = csv.column("reason");
  const int cost = csv.column("us_per_step"), err = csv.column("err_rms"), err_max = csv.column("err_max");
  ASSERT_GE(status, 0);
  ASSERT_GE(reason, 0);
  ASSERT_GE(cost, 0);
  ASSERT_GE(err, 0);
  int ok = 0;
  std::set<std::string> methods;
  for (const auto& row : csv.rows) {
    ASSERT_EQ(row.size(), csv.header.size()) << "ragged row: " << row[0];
    methods.insert(row[csv.column("method")]);
    for (size_t i = 0; i < row.size(); ++i) {
      if (kText.count(csv.header[i])) continue;
      EXPECT_TRUE(finiteOrEmpty(row[i])) << csv.header[i] << " = '" << row[i] << "' in " << row[0] << " "
                                         << row[csv.column("method")];
    }
    if (row[status] == "ok") {
      ++ok;
      EXPECT_TRUE(isNumber(row[cost]) && std::strtod(row[cost].c_str(), nullptr) > 0.0) << row[csv.column("method")];
      EXPECT_TRUE(isNumber(row[err]) && isNumber(row[err_max])) << row[csv.column("method")];
    } else {
      EXPECT_TRUE(row[status] == "failed" || row[status] == "cannot_run") << row[status];
      EXPECT_FALSE(row[reason].empty()) << row[csv.column("method")] << " is " << row[status] << " without a reason";
    }
  }
  EXPECT_GT(ok, 0) << "no run completed";
  // Every solver x integrator x stabilization appears (iterated from EnumNames).
  EXPECT_GE(methods.size(), 3u * 2u * 3u);
}

// The step-control rows: ponyhop's default (RATTLE with 2 deg per substep) completes and splits the
// whipping chain's steps (more than one substep per dt on average at 1/120 s); error control too.
TEST_F(BenchSmoke, StepControlRowsTakeSubsteps) {
  ASSERT_EQ(rc_, 0);
  const Csv csv = readCsv(out_ / "bench.csv");
  const int method = csv.column("method"), step = csv.column("step"), dt = csv.column("dt");
  const int status = csv.column("status"), substeps = csv.column("substeps");
  ASSERT_GE(step, 0);
  int seen = 0;
  for (const auto& row : csv.rows) {
    if (row[csv.column("case")] != "chain8_fixed" ||
        std::abs(std::strtod(row[dt].c_str(), nullptr) - 1.0 / 120) > 1e-9) {
      continue;
    }
    if (row[method] == "tree/rattle/none+auto" || row[method] == "tree/rattle/none+tol") {
      ++seen;
      EXPECT_EQ(row[step], row[method] == "tree/rattle/none+auto" ? "auto" : "tol");
      EXPECT_EQ(row[status], "ok") << row[method] << ": " << row[csv.column("reason")];
      EXPECT_GT(std::strtod(row[substeps].c_str(), nullptr), 1.5) << row[method];
    } else if (row[method] == "tree/rattle/none") {
      EXPECT_EQ(row[step], "fixed");
      EXPECT_DOUBLE_EQ(std::strtod(row[substeps].c_str(), nullptr), 1.0);
    }
  }
  EXPECT_EQ(seen, 2);
}

TEST_F(BenchSmoke, ReferenceAndScalingAreFinite) {
  ASSERT_EQ(rc_, 0);
  for (const char* name : {"reference.csv", "scaling.csv"}) {
    const Csv csv = readCsv(out_ / name);
    ASSERT_FALSE(csv.rows.empty()) << name;
    for (const auto& row : csv.rows) {
      ASSERT_EQ(row.size(), csv.header.size()) << name;
      const bool failed = csv.column("status") >= 0 && row[csv.column("status")] != "ok";
      for (size_t i = 0; i < row.size(); ++i) {
        if (kText.count(csv.header[i])) continue;
        EXPECT_TRUE(finiteOrEmpty(row[i])) << name << ": " << csv.header[i] << " = " << row[i];
        if (!failed && (csv.header[i] == "us_per_step" || csv.header[i] == "max_tip_difference")) {
          EXPECT_TRUE(isNumber(row[i])) << name << ": " << csv.header[i];
        }
      }
    }
  }
}

}  // namespace

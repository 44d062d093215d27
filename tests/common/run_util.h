// Helpers for tests that run the real `ponyhop` executable.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace ponyhop::testing {

// The folder that belongs to the running test: ctest runs tests in parallel, so two tests that
// picked the same scratch or log name (sim_poses, once) must still not share a folder.
inline std::string testOut() {
  std::string dir = std::string(PONYHOP_TEST_OUT) + "/";
  const ::testing::TestInfo* t = ::testing::UnitTest::GetInstance()->current_test_info();
  if (t == nullptr) return dir + "suite";
  std::string name = std::string(t->test_suite_name()) + "." + t->name();
  for (char& c : name)
    if (c == '/') c = '_';
  return dir + name;
}

struct RunResult {
  int code = -1;
  std::string out;  // stdout + stderr
};

// Runs `ponyhop ARGS` from the repository root; captures the output.
inline RunResult runPonyhop(const std::string& args, const std::string& tag) {
  const std::string out = testOut();
  std::filesystem::create_directories(out);
  const std::string log = out + "/" + tag + ".log";
  // Appended piece by piece: GCC 12 at -O3 warns (-Werror=restrict) on `"literal" + std::string&&`.
  std::string cmd = "\"";
  cmd += PONYHOP_EXE;
  cmd += "\" ";
  cmd += args;
  cmd += " > \"";
  cmd += log;
  cmd += "\" 2>&1";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.out = ss.str();
  return r;
}

inline std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void writeFile(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// A fresh scratch folder under the running test's output folder.
inline std::string scratch(const std::string& name) {
  const std::string dir = testOut() + "/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace ponyhop::testing

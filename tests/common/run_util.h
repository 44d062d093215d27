// Helpers for tests that run the real `ponyhop` executable (PONYHOP_EXE: app/ and bench/).
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "common/out_util.h"

namespace ponyhop::testing {

struct RunResult {
  int code = -1;
  std::string out;  // stdout + stderr
};

// Runs a shell command; its exit code, or -1 when it did not exit (a signal).
inline int sh(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

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
  RunResult r;
  r.code = sh(cmd);
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.out = ss.str();
  return r;
}

}  // namespace ponyhop::testing

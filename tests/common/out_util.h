// The tests' output folders (under PONYHOP_TEST_OUT, in the build tree) and whole-file reads and
// writes.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace ponyhop::testing {

// The folder that belongs to the running test: ctest runs tests in parallel, so two tests that
// picked the same scratch or log name (sim_poses, once) must still not share a folder.
inline std::string testOut() {
  // One literal, not `std::string(...) + "/"`: GCC 12 at -O3 warns (-Werror=array-bounds) on that.
  const std::string dir = PONYHOP_TEST_OUT "/";
  const ::testing::TestInfo* t = ::testing::UnitTest::GetInstance()->current_test_info();
  if (t == nullptr) return dir + "suite";
  std::string name = std::string(t->test_suite_name()) + "." + t->name();
  for (char& c : name)
    if (c == '/') c = '_';
  return dir + name;
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

// A folder of the tests' output shared by a test file's tests (not emptied: they write distinct names).
inline std::string outFolder(const std::string& name) {
  const std::string dir = PONYHOP_TEST_OUT "/" + name;
  std::filesystem::create_directories(dir);
  return dir;
}

// A fresh scratch folder under the running test's output folder.
inline std::string scratch(const std::string& name) {
  const std::string dir = testOut() + "/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace ponyhop::testing

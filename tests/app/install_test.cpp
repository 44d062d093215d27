// `cmake --install` into a temporary prefix, then the installed executable run from another
// folder: it finds its scenes, head and clips relative to itself (no source path compiled in),
// and `ponyhop bench` the peer modules this build made.
#include <gtest/gtest.h>

#include <filesystem>

#include "common/run_util.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
using testing::readFile;
using testing::scratch;
using testing::sh;

TEST(Install, InstalledExecutableRunsFromAnyFolder) {
  const std::string root = fs::absolute(scratch("install")).string();
  const std::string prefix = root + "/prefix";
  const std::string build = fs::path(PONYHOP_EXE).parent_path().string();
  ASSERT_EQ(sh("cmake --install " + build + " --prefix " + prefix + " > " + root + "/install.log 2>&1"), 0)
      << readFile(root + "/install.log");
  const std::string exe = prefix + "/bin/ponyhop";
  ASSERT_TRUE(fs::exists(exe));
  EXPECT_TRUE(fs::exists(prefix + "/share/ponyhop/assets/scenes/ponytail.json"));
  EXPECT_TRUE(fs::exists(prefix + "/share/ponyhop/assets/head/head.gltf"));
  EXPECT_TRUE(fs::exists(prefix + "/share/ponyhop/assets/animations/showcase.json"));
  EXPECT_TRUE(fs::exists(prefix + "/share/doc/ponyhop/README.md"));

  // A folder that has no assets/: everything must come from the prefix. The source tree is
  // hidden by running with an environment that has no PONYHOP_DATA_DIR.
  const std::string work = root + "/elsewhere";
  fs::create_directories(work);
  const std::string in = "cd " + work + " && env -u PONYHOP_DATA_DIR " + exe;
  EXPECT_EQ(sh(in + " --version > version.txt 2>&1"), 0);
  EXPECT_NE(readFile(work + "/version.txt").find("ponyhop "), std::string::npos) << readFile(work + "/version.txt");

  EXPECT_EQ(sh(in + " render assets/scenes/ponytail.json --frames 2 --size 96x64 --out frames > render.log 2>&1"), 0)
      << readFile(work + "/render.log");
  EXPECT_TRUE(fs::exists(work + "/frames/frame_00001.png"));
  // A bare scene name works too.
  EXPECT_EQ(sh(in + " sim hopper --duration 0.01 --csv hop.csv > sim.log 2>&1"), 0) << readFile(work + "/sim.log");
  EXPECT_TRUE(fs::exists(work + "/hop.csv"));
  // The chain rows only: what is checked here is that the peer modules load (the hopper and the
  // collider rows cost seconds and are BenchSmoke's).
  EXPECT_EQ(sh(in + " bench --quick --links 8 --anchors fixed --dts 240 --no-scaling --no-hopper --no-collision --out "
                    "bench > bench.log 2>&1"),
            0)
      << readFile(work + "/bench.log");
  EXPECT_TRUE(fs::exists(work + "/bench"));
  // Every peer module built beside the build's executable was installed and loads (the bench's
  // notes name a module that was not found or failed to load).
  const std::string notes = readFile(work + "/bench/README.md");
  for (const auto& entry : fs::directory_iterator(build)) {
    const std::string file = entry.path().filename().string();
    if (file.rfind("ponyhop-peer-", 0) != 0) continue;
    EXPECT_EQ(notes.find(file + " was not found"), std::string::npos) << notes;
    EXPECT_EQ(notes.find(file + " failed to load"), std::string::npos) << notes;
  }
  // A relative scene path is the working directory's first: a scene here shadows the installed one.
  testing::writeFile(work + "/assets/scenes/ponytail.json", "{ \"name\": \"mine\", \"bogus\": 1 }");
  EXPECT_EQ(sh(in + " sim assets/scenes/ponytail.json --duration 0.01 --csv x.csv > mine.log 2>&1"), 2);
  EXPECT_NE(readFile(work + "/mine.log").find("bogus"), std::string::npos) << readFile(work + "/mine.log");
}

}  // namespace
}  // namespace ponyhop

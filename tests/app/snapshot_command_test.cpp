// `ponyhop snapshot SHOTS.txt`: first run writes the golden, a later run passes; a changed
// picture fails with exit 1 and writes expected | actual | diff; --update is refused under CI;
// a missing golden fails under CI and is not written; a golden that does not show its subject is
// never written; a bad shot list exits 2 naming the file, the line and the key.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "app/snapshot.h"
#include "common/run_util.h"
#include "engine/image.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
using testing::readFile;
using testing::runPonyhop;
using testing::scratch;
using testing::writeFile;

// Runs with CI set to `ci` ("" unsets it), whatever the environment of the test run says.
testing::RunResult run(const std::string& args, const std::string& tag, const char* ci = "") {
  if (*ci)
    setenv("CI", ci, 1);
  else
    unsetenv("CI");
  testing::RunResult r = runPonyhop(args, tag);
  unsetenv("CI");
  return r;
}

// A shot list in its own folder (goldens go beside it). The chain mid-swing, small and quick.
std::string makeList(const std::string& dir, const std::string& extra = "") {
  const std::string list = dir + "/shots.txt";
  writeFile(list,
            "# a comment line\n"
            "defaults  size=160x90 light.shadow_size=512\n"
            "swing     assets/scenes/chain.json  t=0.625 subject=chain " +
                extra + "\n");
  return list;
}

TEST(SnapshotCommand, FirstRunWritesTheGoldenThenPasses) {
  const std::string dir = scratch("snap_first");
  const std::string list = makeList(dir);
  auto r = run("snapshot " + list + " --out " + dir + "/out", "snap_first1");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("NEW"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("written (first run)"), std::string::npos) << r.out;
  const Image golden = loadPng(dir + "/swing.png");
  ASSERT_EQ(golden.width, 160);
  ASSERT_EQ(golden.height, 90);
  EXPECT_TRUE(fs::exists(dir + "/RENDERER.txt"));

  r = run("snapshot " + list + " --out " + dir + "/out", "snap_first2", "true");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("PASS  swing"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/out/swing.compare.png"));
}

TEST(SnapshotCommand, ChangedPictureFailsWithComposite) {
  const std::string dir = scratch("snap_fail");
  const std::string list = makeList(dir);
  ASSERT_EQ(run("snapshot " + list, "snap_fail1").code, 0);
  // The golden from another moment: the chain is elsewhere.
  const std::string later = dir + "/later.txt";
  writeFile(later, "swing assets/scenes/chain.json t=0.9 size=160x90 light.shadow_size=512\n");
  ASSERT_EQ(run("snapshot " + later + " --goldens " + dir + "/later", "snap_fail2").code, 0);
  fs::copy_file(dir + "/later/swing.png", dir + "/swing.png", fs::copy_options::overwrite_existing);
  const Image golden = loadPng(dir + "/swing.png");

  const auto r = run("snapshot " + list + " --out " + dir + "/out", "snap_fail3", "true");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("FAIL  swing"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("expected | actual | diff"), std::string::npos) << r.out;
  const Image actual = loadPng(dir + "/out/swing.actual.png");
  const Image composite = loadPng(dir + "/out/swing.compare.png");
  ASSERT_FALSE(actual.empty());
  ASSERT_FALSE(composite.empty());
  // Three pictures side by side with a 6 px frame: expected at x = 6, actual at x = 172.
  EXPECT_EQ(composite.width, 3 * 160 + 4 * 6);
  EXPECT_EQ(composite.height, 90 + 2 * 6);
  for (int y = 0; y < 90; y += 7) {
    for (int x = 0; x < 160; x += 5) {
      ASSERT_EQ(0, std::memcmp(composite.px(6 + x, 6 + y), golden.px(x, y), 4)) << x << "," << y;
      ASSERT_EQ(0, std::memcmp(composite.px(172 + x, 6 + y), actual.px(x, y), 4)) << x << "," << y;
    }
  }
  // The diff third has red where the chain moved.
  int red = 0;
  for (int y = 0; y < 90; ++y)
    for (int x = 0; x < 160; ++x) {
      const uint8_t* p = composite.px(338 + x, 6 + y);
      red += p[0] == 255 && p[1] == 0 && p[2] == 0;
    }
  EXPECT_GT(red, 20);
  // The golden is untouched by a failing run.
  EXPECT_EQ(readFile(dir + "/swing.png"), readFile(dir + "/later/swing.png"));
}

TEST(SnapshotCommand, UpdateRefusedUnderCiAndWorksOtherwise) {
  const std::string dir = scratch("snap_update");
  const std::string list = makeList(dir);
  ASSERT_EQ(run("snapshot " + list, "snap_update1").code, 0);
  Image tampered = loadPng(dir + "/swing.png");
  for (int x = 0; x < 160; ++x) tampered.px(x, 40)[0] ^= 0xff;
  ASSERT_TRUE(savePng(dir + "/swing.png", tampered));
  const std::string before = readFile(dir + "/swing.png");

  auto r = run("snapshot " + list + " --update", "snap_update2", "true");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--update is refused under CI=true"), std::string::npos) << r.out;
  EXPECT_EQ(readFile(dir + "/swing.png"), before);

  r = run("snapshot " + list + " --update", "snap_update3", "false");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("UPDATED"), std::string::npos) << r.out;
  EXPECT_NE(readFile(dir + "/swing.png"), before);
  EXPECT_EQ(run("snapshot " + list, "snap_update4", "true").code, 0);
}

TEST(SnapshotCommand, MissingGoldenFailsUnderCiAndIsNotWritten) {
  const std::string dir = scratch("snap_ci");
  const auto r = run("snapshot " + makeList(dir), "snap_ci", "true");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("no golden"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/swing.png"));
}

// The camera turned away from the chain: an empty floor is never recorded as a golden.
TEST(SnapshotCommand, GoldenWithoutItsSubjectIsRejected) {
  const std::string dir = scratch("snap_empty");
  const std::string list = makeList(dir, "camera.target=[10,-1.25,0.05]");
  auto r = run("snapshot " + list, "snap_empty1");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("golden NOT written"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("chain covers"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/swing.png"));
  r = run("snapshot " + list + " --update", "snap_empty2");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/swing.png"));
  // Without naming the subject, "everything the scene has" is checked just the same.
  writeFile(list, "swing assets/scenes/chain.json t=0.625 size=160x90 camera.target=[10,-1.25,0.05]\n");
  r = run("snapshot " + list, "snap_empty3");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("everything covers"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/swing.png"));
}

TEST(SnapshotCommand, BadShotListsExit2NamingLineAndKey) {
  const std::string dir = scratch("snap_bad");
  struct Case {
    std::string line, expect;
  };
  const Case cases[] = {
      {"a assets/scenes/chain.json speed=3", "shots.txt:1: 'speed' is not a shot option"},
      {"a assets/scenes/chain.json t=-1", "t=-1: a time in seconds"},
      {"a assets/scenes/chain.json size=big", "size=big: expected WIDTHxHEIGHT"},
      {"a assets/scenes/chain.json threshold=2", "threshold=2: a number in [0, 1]"},
      {"a assets/scenes/nope.json", "scene assets/scenes/nope.json not found"},
      {"a assets/scenes/chain.json chain.links=0", "chain.links"},
      {"a assets/scenes/chain.json subject=hopper", "has no hopper"},
      {"a assets/scenes/chain.json wait=stance", "wait=stance: the scene has no hopper"},
      {"a/b assets/scenes/chain.json", "shot name 'a/b'"},
      {"a assets/scenes/chain.json\na assets/scenes/chain.json", "shots.txt:2: shot name 'a' is used twice"},
  };
  for (const Case& c : cases) {
    writeFile(dir + "/shots.txt", c.line + "\n");
    const auto r = run("snapshot " + dir + "/shots.txt", "snap_bad");
    EXPECT_EQ(r.code, 2) << c.line << "\n" << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.line << "\n" << r.out;
  }
  EXPECT_FALSE(fs::exists(dir + "/a.png"));
  EXPECT_EQ(run("snapshot " + dir + "/missing.txt", "snap_bad2").code, 2);
}

// The parser on its own: defaults carry over, quotes group, a key with a dot is a scene field.
TEST(ShotListParse, DefaultsQuotesAndOverrides) {
  const std::string dir = scratch("snap_parse");
  writeFile(dir + "/s.txt",
            "defaults size=64x48 threshold=0.05\n"
            "one assets/scenes/ponytail.json t=1.5 \"head.mesh=assets/head/head.gltf\" max_share=0.01 # note\n"
            "defaults size=32x32\n"
            "two assets/scenes/hopper.json wait=stance subject=hopper min_subject=0.02\n");
  const ShotList l = loadShotList(dir + "/s.txt");
  ASSERT_EQ(l.shots.size(), 2u);
  EXPECT_EQ(l.golden_dir, dir);
  const Shot& a = l.shots[0];
  EXPECT_EQ(a.name, "one");
  EXPECT_EQ(a.t, 1.5);
  EXPECT_EQ(a.width, 64);
  EXPECT_EQ(a.diff.threshold, 0.05);
  EXPECT_EQ(a.diff.max_diff_share, 0.01);
  ASSERT_EQ(a.sets.size(), 1u);
  EXPECT_EQ(a.sets[0], "head.mesh=assets/head/head.gltf");
  const Shot& b = l.shots[1];
  EXPECT_EQ(b.width, 32);
  EXPECT_EQ(b.diff.threshold, 0.05);  // the first defaults line still holds
  EXPECT_EQ(b.wait, "stance");
  EXPECT_EQ(b.min_subject, 0.02);
  EXPECT_EQ(shotScene(b).render.width, 32);
}

}  // namespace
}  // namespace ponyhop

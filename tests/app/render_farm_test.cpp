// The render farm (docs/RENDER_FARM.md): chunks rendered with `--range` through GNU parallel give
// the same bytes as one full run; `--resume` renders only what is missing; the merged folder
// encodes into a video. Also the transparent background and the video containers.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>

#include "common/run_util.h"
#include "engine/frame_writer.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
using testing::readFile;
using testing::runPonyhop;
using testing::scratch;
using testing::sh;

double seconds(const std::string& cmd) {
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(sh(cmd), 0) << cmd;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The follow camera carries state from frame to frame: the hopper scene checks that a chunk
// replays it.
const char* kScene = "assets/scenes/ponytail_hopper.json --set camera.mode=follow";
constexpr int kFrames = 16;

TEST(RenderFarm, TwoChunksThroughParallelMatchOneRunByteForByte) {
  const std::string dir = fs::absolute(scratch("render_farm")).string();
  const std::string common = std::string(kScene) + " --frames " + std::to_string(kFrames) + " --size 160x96";
  const double t_full =
      seconds(std::string(PONYHOP_EXE) + " render " + common + " --out " + dir + "/full 2> " + dir + "/full.log");
  // Two chunks, two jobs at once, as docs/RENDER_FARM.md shows.
  const double t_farm = seconds("parallel -j2 --halt now,fail=1 " + std::string(PONYHOP_EXE) + " render " + common +
                                " --out " + dir + "/farm --range {} ::: 0:7 8:15 2> " + dir + "/farm.log");
  std::printf("full run %.2f s, two chunks through parallel -j2 %.2f s\n", t_full, t_farm);
  for (int i = 0; i < kFrames; ++i) {
    const std::string a = readFile(FrameWriter::framePath(dir + "/full", i));
    const std::string b = readFile(FrameWriter::framePath(dir + "/farm", i));
    ASSERT_FALSE(a.empty()) << i;
    EXPECT_TRUE(a == b) << "frame " << i << " differs";
  }
  EXPECT_FALSE(fs::exists(FrameWriter::framePath(dir + "/farm", kFrames)));
  const auto v = runPonyhop("video " + dir + "/farm --out " + dir + "/farm.mp4 --fps 30", "render_farm_video");
  EXPECT_EQ(v.code, 0) << v.out;
  EXPECT_GT(fs::file_size(dir + "/farm.mp4"), 1000u);

  // --resume: a frame removed (and one cut short) is rendered again, the others are kept as they are.
  fs::remove(FrameWriter::framePath(dir + "/farm", 3));
  fs::resize_file(FrameWriter::framePath(dir + "/farm", 9), 100);
  const auto before = fs::last_write_time(FrameWriter::framePath(dir + "/farm", 5));
  const auto r = runPonyhop("render " + common + " --out " + dir + "/farm --resume", "render_farm_resume");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("2 rendered, 14 already there"), std::string::npos) << r.out;
  EXPECT_EQ(fs::last_write_time(FrameWriter::framePath(dir + "/farm", 5)), before);
  for (int i : {3, 9}) {
    EXPECT_TRUE(readFile(FrameWriter::framePath(dir + "/full", i)) ==
                readFile(FrameWriter::framePath(dir + "/farm", i)))
        << "frame " << i;
  }
}

TEST(RenderFarm, BadRangesAreRefused) {
  const std::string dir = scratch("render_farm_bad");
  for (const char* bad : {"5:2", "0:99", "x", "-1:3"}) {
    const auto r =
        runPonyhop("render assets/scenes/chain.json --frames 10 --size 64x64 --out " + dir + "/o --range " + bad,
                   "render_farm_bad");
    EXPECT_EQ(r.code, 2) << bad << ": " << r.out;
    EXPECT_NE(r.out.find("--range"), std::string::npos) << r.out;
  }
  EXPECT_FALSE(fs::exists(dir + "/o"));
}

TEST(Video, ContainerFollowsTheExtensionOrIsRefused) {
  const std::string dir = scratch("video_containers");
  const auto r =
      runPonyhop("render assets/scenes/chain.json --frames 4 --size 64x48 --out " + dir + "/f", "video_frames");
  ASSERT_EQ(r.code, 0) << r.out;
  // Magic bytes of each container.
  const auto starts = [](const std::string& s, size_t at, const std::string& magic) {
    return s.size() >= at + magic.size() && s.compare(at, magic.size(), magic) == 0;
  };
  for (const char* ext : {"mp4", "mov", "webm", "gif"}) {
    const std::string out = dir + "/v." + ext;
    const auto v = runPonyhop("video " + dir + "/f --out " + out, std::string("video_") + ext);
    ASSERT_EQ(v.code, 0) << v.out;
    const std::string bytes = readFile(out);
    if (std::string(ext) == "gif") {
      EXPECT_TRUE(starts(bytes, 0, "GIF89a")) << ext;
    }
    if (std::string(ext) == "webm") {
      EXPECT_TRUE(starts(bytes, 0, "\x1a\x45\xdf\xa3")) << ext;
    }
    if (std::string(ext) == "mp4") {
      EXPECT_TRUE(starts(bytes, 4, "ftypisom")) << ext;
    }
    if (std::string(ext) == "mov") {
      EXPECT_TRUE(starts(bytes, 4, "ftypqt")) << ext;
    }
  }
  const auto bad = runPonyhop(
      "render assets/scenes/chain.json --frames 2 --size 64x48 --out " + dir + "/g --video " + dir + "/x.avi",
      "video_bad");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find(".webm"), std::string::npos) << bad.out;
  EXPECT_FALSE(fs::exists(dir + "/g"));
}

TEST(Transparent, BackgroundHasAlphaZeroAndTheObjectIsOpaque) {
  const std::string dir = scratch("transparent");
  const auto r = runPonyhop(
      "render assets/scenes/head.json --frames 1 --size 96x96 --transparent --set render.ground=false --out " + dir,
      "transparent");
  ASSERT_EQ(r.code, 0) << r.out;
  std::string err;
  const auto img = readPng(FrameWriter::framePath(dir, 0), &err);
  ASSERT_TRUE(img) << err;
  int clear = 0, opaque = 0;
  for (size_t i = 3; i < img->rgba.size(); i += 4) {
    clear += img->rgba[i] == 0;
    opaque += img->rgba[i] == 255;
  }
  const int n = int(img->rgba.size() / 4);
  EXPECT_GT(clear, n / 4) << "the background is transparent";
  EXPECT_GT(opaque, n / 20) << "the head is opaque";
  EXPECT_EQ(img->rgba[3], 0) << "a corner shows the background";
}

}  // namespace
}  // namespace ponyhop

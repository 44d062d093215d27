// PNG output (atomic files, async writer) and mp4 encoding with ffmpeg.
#include "engine/frame_writer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "engine/video.h"

using namespace ponyhop;
namespace fs = std::filesystem;

namespace {

std::string freshDir(const std::string& name) {
  const fs::path d = fs::path(PONYHOP_TEST_OUT) / "frame_writer" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

// Deterministic test picture: gradients + a moving square, opaque.
std::vector<uint8_t> picture(int w, int h, int frame) {
  std::vector<uint8_t> px(size_t(w) * size_t(h) * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = px.data() + (size_t(y) * size_t(w) + size_t(x)) * 4;
      const bool sq = std::abs(x - (frame * 3) % w) < 6 && std::abs(y - h / 2) < 6;
      p[0] = uint8_t(sq ? 230 : (x * 255) / std::max(w - 1, 1));
      p[1] = uint8_t(sq ? 40 : (y * 255) / std::max(h - 1, 1));
      p[2] = uint8_t((x * 7 + y * 13 + frame) & 255);
      p[3] = 255;
    }
  return px;
}

std::vector<std::string> tmpFiles(const std::string& dir) {
  std::vector<std::string> t;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".tmp") t.push_back(e.path().string());
  return t;
}

}  // namespace

TEST(FrameWriter, WritePngAtomicRoundTrips) {
  const std::string dir = freshDir("single");
  const auto px = picture(37, 21, 3);
  const std::string path = dir + "/a.png";
  std::string err;
  ASSERT_TRUE(writePngAtomic(path, 37, 21, px.data(), &err)) << err;
  EXPECT_TRUE(tmpFiles(dir).empty());
  const auto img = readPng(path, &err);
  ASSERT_TRUE(img) << err;
  EXPECT_EQ(img->width, 37);
  EXPECT_EQ(img->height, 21);
  EXPECT_TRUE(img->rgba == px) << "decoded pixels differ";

  // Errors name the file.
  EXPECT_FALSE(writePngAtomic(dir + "/no/such/folder/b.png", 37, 21, px.data(), &err));
  EXPECT_NE(err.find("no/such/folder/b.png"), std::string::npos) << err;
  EXPECT_FALSE(readPng(dir + "/missing.png", &err));
  EXPECT_NE(err.find("missing.png"), std::string::npos) << err;
}

TEST(FrameWriter, AsyncFramesAreCompleteAndAtomic) {
  const std::string dir = freshDir("seq");
  const int w = 96, h = 64, n = 24;
  {
    FrameWriter fw(dir, 2, 3);
    for (int i = 0; i < n; ++i) ASSERT_TRUE(fw.push(i, w, h, picture(w, h, i)));
    std::string err;
    ASSERT_TRUE(fw.finish(&err)) << err;
    EXPECT_EQ(fw.framesWritten(), n);
    EXPECT_GT(fw.meanEncodeMs(), 0.0);
  }
  EXPECT_TRUE(tmpFiles(dir).empty()) << tmpFiles(dir).front();
  for (int i = 0; i < n; ++i) {
    const std::string path = FrameWriter::framePath(dir, i);
    std::string err;
    const auto img = readPng(path, &err);
    ASSERT_TRUE(img) << err;
    EXPECT_TRUE(img->rgba == picture(w, h, i)) << path;
  }
  EXPECT_EQ(fs::path(FrameWriter::framePath(dir, 7)).filename(), "frame_00007.png");
}

TEST(FrameWriter, WriteErrorsAreReported) {
  // The "folder" is a regular file: nothing can be written under it.
  const std::string base = freshDir("err");
  const std::string file = base + "/not_a_folder";
  std::ofstream(file) << "x";
  FrameWriter fw(file + "/frames", 1, 2);
  std::string err;
  bool pushed_all = true;
  for (int i = 0; i < 4 && pushed_all; ++i) pushed_all = fw.push(i, 8, 8, picture(8, 8, i), &err);
  const bool finished = fw.finish(&err);
  EXPECT_FALSE(pushed_all && finished);
  EXPECT_NE(err.find("not_a_folder"), std::string::npos) << err;
  EXPECT_EQ(fw.framesWritten(), 0);
}

TEST(FrameWriter, EncodeTimeOf720pFrame) {
  // Not a speed assertion: prints the number quoted in docs/RENDERING.md.
  const std::string dir = freshDir("t720");
  const auto px = picture(1280, 720, 0);
  std::string err;
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(writePngAtomic(dir + "/f.png", 1280, 720, px.data(), &err)) << err;
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("PNG 1280x720 synthetic, zlib level %d: %.1f ms, %.0f KiB\n", kPngZlibLevel, ms,
              double(fs::file_size(dir + "/f.png")) / 1024.0);
}

TEST(Video, EncodesAnMp4FromFrames) {
  if (!ffmpegAvailable()) GTEST_SKIP() << "the ffmpeg program is not installed (apt install ffmpeg)";
  const std::string dir = freshDir("video");
  const int w = 65, h = 49;  // odd: must be padded for yuv420p
  {
    FrameWriter fw(dir, 2, 4);
    for (int i = 0; i < 15; ++i) ASSERT_TRUE(fw.push(i, w, h, picture(w, h, i)));
    ASSERT_TRUE(fw.finish());
  }
  const std::string mp4 = dir + "/out/clip.mp4";
  VideoOptions opt;
  opt.fps = 30;
  std::string err;
  ASSERT_TRUE(encodeVideo(dir, mp4, opt, &err)) << err;
  ASSERT_TRUE(fs::exists(mp4));
  EXPECT_GT(fs::file_size(mp4), 500u);
  EXPECT_FALSE(fs::exists(mp4 + ".tmp"));
  // An mp4 starts with an ftyp box.
  std::ifstream f(mp4, std::ios::binary);
  char head[8] = {};
  f.read(head, 8);
  EXPECT_EQ(std::string(head + 4, 4), "ftyp");
}

TEST(Video, ClearErrors) {
  const std::string dir = freshDir("video_err");
  std::string err;
  // No frames.
  EXPECT_FALSE(encodeVideo(dir, dir + "/x.mp4", VideoOptions{}, &err));
  EXPECT_NE(err.find("frame_00000.png"), std::string::npos) << err;
  // Missing program.
  ASSERT_TRUE(writePngAtomic(FrameWriter::framePath(dir, 0), 4, 4, picture(4, 4, 0).data(), &err)) << err;
  VideoOptions opt;
  opt.ffmpeg = "/nonexistent/ffmpeg";
  EXPECT_FALSE(encodeVideo(dir, dir + "/x.mp4", opt, &err));
  EXPECT_NE(err.find("ffmpeg"), std::string::npos) << err;
  EXPECT_FALSE(ffmpegAvailable(opt.ffmpeg));
  if (!ffmpegAvailable()) GTEST_SKIP() << "ffmpeg not installed: its failure message cannot be checked";
  // ffmpeg itself fails (a corrupt PNG): its stderr tail is in the message.
  std::ofstream(FrameWriter::framePath(dir, 0), std::ios::binary) << "not a png";
  EXPECT_FALSE(encodeVideo(dir, dir + "/x.mp4", VideoOptions{}, &err));
  EXPECT_NE(err.find("ffmpeg failed"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/x.mp4"));
  EXPECT_FALSE(fs::exists(dir + "/x.mp4.tmp"));
}

// `ponyhop run` in a real window under Xvfb: a fixed number of frames, a screenshot, exit. The
// screenshot must show both the scene and the panel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "app/panel.h"
#include "engine/frame_writer.h"
#include "common/run_util.h"

namespace ponyhop {
namespace {

double lumaStddev(const Image& img, int x0, int x1) {
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = img.px(x, y);
      const double l = 0.3 * p[0] + 0.59 * p[1] + 0.11 * p[2];
      sum += l;
      sum2 += l * l;
      ++n;
    }
  }
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

int countColours(const Image& img, int x0, int x1) {
  std::vector<bool> seen(4096, false);
  int colours = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = img.px(x, y);
      const int q = (p[0] >> 4) << 8 | (p[1] >> 4) << 4 | (p[2] >> 4);
      if (!seen[size_t(q)]) seen[size_t(q)] = true, ++colours;
    }
  }
  return colours;
}

TEST(WindowTest, RunUnderXvfbShowsTheSceneAndThePanel) {
#ifndef PONYHOP_WINDOW
  GTEST_SKIP() << "built without the window (-DPONYHOP_WINDOW=OFF): no `ponyhop run`";
#else
  if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "xvfb-run is missing (apt-get install xvfb): this test needs an X server for the window";
  }
  const std::string dir = testing::scratch("window");
  const std::string shot = dir + "/run.png";
  // The window needs an X server around the executable (runPonyhop runs it bare).
  const std::string cmd = "xvfb-run -a -s '-screen 0 1280x720x24' " + std::string(PONYHOP_EXE) +
                          " run assets/scenes/ponytail.json --frames 20 --size 1280x720 --no-vsync --screenshot " +
                          shot + " > " + dir + "/run.log 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string log = testing::readFile(dir + "/run.log");
  ASSERT_EQ(status, 0) << log;
  EXPECT_NE(log.find("frame time"), std::string::npos) << "the run reports its frame time\n" << log;
  std::string err;
  const auto img = readPng(shot, &err);
  ASSERT_TRUE(img.has_value()) << err << "\n" << log;
  ASSERT_EQ(img->width, 1280);
  ASSERT_EQ(img->height, 720);
  const int scene_w = 1280 - Panel::kDefaultWidth;
  EXPECT_GT(lumaStddev(*img, 0, scene_w), 5.0) << "the scene view shows something";
  EXPECT_GT(countColours(*img, 0, scene_w), 20) << "shaded head, hair and ground";
  EXPECT_GT(lumaStddev(*img, scene_w, 1280), 5.0) << "the panel shows something";
  EXPECT_GT(countColours(*img, scene_w, 1280), 12) << "text, sliders and headers";
#endif
}

}  // namespace
}  // namespace ponyhop

// The snapshot comparator (engine/image_diff) and `ponyhop diff`, on synthetic pictures drawn
// here with supersampled anti-aliasing, so that edges look like a renderer's.
#include "engine/image_diff.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <zlib.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include "common/run_util.h"
#include "engine/image.h"

namespace ponyhop {
namespace {

struct Rgb {
  uint8_t r, g, b;
};

constexpr int kSS = 8;  // 8x8 samples per pixel: 65 coverage levels, like a renderer's MSAA resolve

// Blends `c` into pixel (x, y) with coverage `cov` in [0, 1].
void blendPixel(Image& img, int x, int y, Rgb c, double cov) {
  if (cov <= 0) return;
  uint8_t* p = img.px(x, y);
  p[0] = static_cast<uint8_t>(std::lround(p[0] + (c.r - p[0]) * cov));
  p[1] = static_cast<uint8_t>(std::lround(p[1] + (c.g - p[1]) * cov));
  p[2] = static_cast<uint8_t>(std::lround(p[2] + (c.b - p[2]) * cov));
}

// Anti-aliased disc of centre (cx, cy) and radius r in pixel units (pixel (0,0) spans [0,1)^2).
void drawDisc(Image& img, double cx, double cy, double r, Rgb c) {
  for (int y = std::max(0, int(cy - r) - 1); y <= std::min(img.height - 1, int(cy + r) + 1); ++y) {
    for (int x = std::max(0, int(cx - r) - 1); x <= std::min(img.width - 1, int(cx + r) + 1); ++x) {
      int in = 0;
      for (int j = 0; j < kSS; ++j) {
        for (int i = 0; i < kSS; ++i) {
          const double sx = x + (i + 0.5) / kSS - cx, sy = y + (j + 0.5) / kSS - cy;
          in += sx * sx + sy * sy <= r * r;
        }
      }
      blendPixel(img, x, y, c, double(in) / (kSS * kSS));
    }
  }
}

// Anti-aliased axis-aligned rectangle [x0, x1) x [y0, y1) in pixel units.
void drawRect(Image& img, double x0, double y0, double x1, double y1, Rgb c) {
  for (int y = std::max(0, int(y0) - 1); y <= std::min(img.height - 1, int(y1) + 1); ++y) {
    for (int x = std::max(0, int(x0) - 1); x <= std::min(img.width - 1, int(x1) + 1); ++x) {
      const double cx = std::max(0.0, std::min(x + 1.0, x1) - std::max(double(x), x0));
      const double cy = std::max(0.0, std::min(y + 1.0, y1) - std::max(double(y), y0));
      blendPixel(img, x, y, c, cx * cy);
    }
  }
}

constexpr Rgb kBackground{235, 238, 242}, kDark{40, 50, 70}, kOrange{230, 120, 30}, kBlue{40, 90, 200};

// A small "scene": background, a ground bar, two discs. `dx`, `dy` shift the discs (sub-pixel).
Image scene(double dx = 0, double dy = 0, bool with_bar = true, int w = 160, int h = 120) {
  Image img(w, h, kBackground.r, kBackground.g, kBackground.b);
  if (with_bar) drawRect(img, 10.0, 95.0, 150.0, 103.0, kDark);
  drawDisc(img, 55.3 + dx, 50.6 + dy, 28.0, kOrange);
  drawDisc(img, 112.7 + dx, 58.2 + dy, 17.5, kBlue);
  return img;
}

const uint8_t* at(const Image& img, int x, int y) { return img.px(x, y); }

TEST(ImageDiff, IdenticalImagesPass) {
  const Image a = scene(), b = scene();
  Image diff;
  const DiffResult r = compareImages(a, b, DiffOptions{}, &diff);
  EXPECT_TRUE(r.same_size);
  EXPECT_TRUE(r.pass) << r.message;
  EXPECT_EQ(r.differing, 0);
  EXPECT_EQ(r.antialiased, 0);
  EXPECT_EQ(r.pixels, 160L * 120L);
  EXPECT_NEAR(r.max_delta, 0.0, 1e-12);
  ASSERT_EQ(diff.width, a.width);
  ASSERT_EQ(diff.height, a.height);
}

TEST(ImageDiff, YiqScaleAndAlphaOverWhite) {
  const uint8_t red[4] = {255, 0, 0, 255}, cyan[4] = {0, 255, 255, 255};
  const uint8_t white[4] = {255, 255, 255, 255}, clear_black[4] = {0, 0, 0, 0}, black[4] = {0, 0, 0, 255};
  EXPECT_NEAR(yiqDelta(red, cyan), kMaxYiqDelta, 1.0);   // the largest distance: the scale of t
  EXPECT_NEAR(yiqDelta(white, clear_black), 0.0, 1e-9);  // transparent = background white
  EXPECT_GT(yiqDelta(white, black), 0.9 * kMaxYiqDelta);
}

TEST(ImageDiff, SmallNoiseBelowThresholdPasses) {
  const Image a = scene();
  Image b = a;
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> noise(-2, 2);
  for (size_t i = 0; i < b.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    b.rgba[i] = static_cast<uint8_t>(std::clamp(int(b.rgba[i]) + noise(rng), 0, 255));
  }
  const DiffResult r = compareImages(a, b, DiffOptions{}, nullptr);
  EXPECT_TRUE(r.pass) << r.message;
  EXPECT_EQ(r.differing, 0);
  EXPECT_GT(r.max_delta, 0.0);   // the noise is seen...
  EXPECT_LT(r.max_delta, 0.05);  // ...and is far below t = 0.1
  // A zero threshold counts every changed pixel: the noise is there to be found.
  DiffOptions strict;
  strict.threshold = 0.0;
  EXPECT_FALSE(compareImages(a, b, strict, nullptr).pass);
}

TEST(ImageDiff, SubPixelShiftOfAntialiasedEdgesPasses) {
  // Same scene, discs re-rendered 0.3 px right and 0.3 px down: every disc edge pixel changes
  // its coverage, often well over the colour threshold, but only as anti-aliasing.
  const Image a = scene(0, 0), b = scene(0.3, 0.3);
  Image diff;
  const DiffResult r = compareImages(a, b, DiffOptions{}, &diff);
  EXPECT_TRUE(r.pass) << r.message << " (antialiased " << r.antialiased << ")";
  EXPECT_GT(r.antialiased, 50);  // many edge pixels exceeded the threshold and were excused
  // Without the anti-aliasing detector the same pair fails: the detector is what passes it.
  DiffOptions no_aa;
  no_aa.detect_antialiasing = false;
  const DiffResult raw = compareImages(a, b, no_aa, nullptr);
  EXPECT_FALSE(raw.pass);
  EXPECT_EQ(raw.differing, r.differing + r.antialiased);
  // Excused pixels are yellow in the diff image.
  long yellow = 0;
  for (int y = 0; y < diff.height; ++y)
    for (int x = 0; x < diff.width; ++x) {
      const uint8_t* p = at(diff, x, y);
      yellow += p[0] == 255 && p[1] == 255 && p[2] == 0;
    }
  EXPECT_EQ(yellow, r.antialiased);
}

TEST(ImageDiff, OnePixelShiftOfSmoothEdgesPasses) {
  // Discs moved by a whole pixel (and by 0.7 px the other way) and re-rendered: smooth curved
  // edges keep blending between the same two flat areas, so only anti-aliasing changes.
  for (auto [dx, dy] : {std::pair{1.0, 0.0}, std::pair{0.0, 1.0}, std::pair{0.7, -0.4}}) {
    const DiffResult r = compareImages(scene(0, 0), scene(dx, dy), DiffOptions{}, nullptr);
    EXPECT_TRUE(r.pass) << "shift " << dx << "," << dy << ": " << r.message << " (antialiased " << r.antialiased << ")";
    EXPECT_GT(r.antialiased, 100);
  }
  // Two pixels is a real move: too many pixels change beyond what an edge blend explains.
  EXPECT_FALSE(compareImages(scene(0, 0), scene(2.0, 1.0), DiffOptions{}, nullptr).pass);
}

TEST(ImageDiff, AntialiasingNeedsFlatSidesInBothImages) {
  // A vertical edge: black columns 0..19, a grey blend column 20, white columns 21..39.
  auto edge = [](uint8_t blend) {
    Image img(40, 40, 255, 255, 255);
    for (int y = 0; y < 40; ++y) {
      for (int x = 0; x < 20; ++x) img.px(x, y)[0] = img.px(x, y)[1] = img.px(x, y)[2] = 0;
      img.px(20, y)[0] = img.px(20, y)[1] = img.px(20, y)[2] = blend;
    }
    return img;
  };
  const Image expected = edge(128);
  // Same edge, other coverage: the blend column is excused (yellow), nothing counts.
  Image diff;
  const DiffResult moved = compareImages(expected, edge(60), DiffOptions{}, &diff);
  EXPECT_EQ(moved.differing, 0);
  EXPECT_EQ(moved.antialiased, 40);
  EXPECT_EQ(diff.px(20, 10)[2], 0);  // yellow: R = G = 255, B = 0
  // Same change of the blend column, but the two sides next to it are now textured (no pixel
  // equals a neighbour): the sides are flat only in `expected`, so the blend is no longer
  // explained by anti-aliasing between flat areas present in both pictures, and it counts.
  Image textured = edge(60);
  for (int y = 0; y < 40; ++y)
    for (int x : {18, 19, 21, 22}) {
      const int v = (x * 7 + y * 13) % 31;  // steps of 7, 13, 6, 20 (mod 31): never equal
      uint8_t* p = textured.px(x, y);
      p[0] = p[1] = p[2] = static_cast<uint8_t>(x < 20 ? v : 255 - v);
    }
  const DiffResult r = compareImages(expected, textured, DiffOptions{}, &diff);
  for (int y = 0; y < 40; ++y) {
    const uint8_t* p = diff.px(20, y);
    EXPECT_TRUE(p[0] == 255 && p[1] == 0 && p[2] == 0) << "blend pixel 20," << y << " should count (red)";
  }
  EXPECT_FALSE(r.pass);
}

TEST(ImageDiff, ThinFeaturesAreNotMistakenForAntialiasing) {
  // A new 1-px hairline has only brighter neighbours (no darker side): not an edge blend.
  const Image plain(160, 120, 255, 255, 255);
  Image hairline = plain;
  for (int x = 20; x < 140; ++x) hairline.px(x, 60)[0] = hairline.px(x, 60)[1] = hairline.px(x, 60)[2] = 30;
  const DiffResult h = compareImages(plain, hairline, DiffOptions{}, nullptr);
  EXPECT_EQ(h.differing, 120);
  EXPECT_FALSE(h.pass);
  // A checker of 2x2 blocks (black, grey / grey, white) whose grey changes: every grey pixel
  // touches black and white (like an edge blend) but sits in a 2x2 patch of its own: content.
  auto checker = [](uint8_t grey) {
    Image img(160, 120);
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) {
        const bool bx = (x / 2) % 2, by = (y / 2) % 2;
        const uint8_t v = bx == by ? (bx ? 255 : 0) : grey;
        img.px(x, y)[0] = img.px(x, y)[1] = img.px(x, y)[2] = v;
      }
    return img;
  };
  const DiffResult c = compareImages(checker(100), checker(160), DiffOptions{}, nullptr);
  EXPECT_EQ(c.differing, 160 * 120 / 2);
  EXPECT_EQ(c.antialiased, 0);
  // A column between a black and a white hairline changes grey: its darkest and brightest
  // neighbours are 1 px wide (2 identical neighbours, not flat), so nothing explains it as a blend.
  auto lines = [](uint8_t between) {
    Image img(160, 120, 128, 128, 128);
    for (int y = 10; y < 110; ++y) {
      img.px(20, y)[0] = img.px(20, y)[1] = img.px(20, y)[2] = 0;
      img.px(21, y)[0] = img.px(21, y)[1] = img.px(21, y)[2] = between;
      img.px(22, y)[0] = img.px(22, y)[1] = img.px(22, y)[2] = 255;
    }
    return img;
  };
  const DiffResult l = compareImages(lines(128), lines(60), DiffOptions{}, nullptr);
  EXPECT_EQ(l.differing, 100);
  EXPECT_EQ(l.antialiased, 0);
}

// Fills [x0, x1) x [y0, y1) of `img` by adding `dr`, `dg`, `db` to each channel.
void shiftPatch(Image& img, int x0, int y0, int x1, int y1, int dr, int dg, int db) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      uint8_t* p = img.px(x, y);
      p[0] = static_cast<uint8_t>(std::clamp(p[0] + dr, 0, 255));
      p[1] = static_cast<uint8_t>(std::clamp(p[1] + dg, 0, 255));
      p[2] = static_cast<uint8_t>(std::clamp(p[2] + db, 0, 255));
    }
}

TEST(ImageDiff, VisibleColourChangeOfARegionFails) {
  // A 40x40 patch of mid grey made redder. Red weighs little in YIQ: a +30/255 red shift alone
  // has normalized distance ~0.064, under the default t = 0.1 (pixelmatch's calibration); a
  // +60/255 red shift (0.128) or a +30/255 grey shift (0.114) is caught.
  Image a(120, 100, 128, 128, 128);
  Image red30 = a, red60 = a, grey30 = a;
  shiftPatch(red30, 40, 30, 80, 70, 30, 0, 0);
  shiftPatch(red60, 40, 30, 80, 70, 60, 0, 0);
  shiftPatch(grey30, 40, 30, 80, 70, 30, 30, 30);

  const DiffResult r60 = compareImages(a, red60, DiffOptions{}, nullptr);
  EXPECT_FALSE(r60.pass);
  EXPECT_EQ(r60.differing, 40 * 40);  // a flat patch has no anti-aliasing to excuse
  EXPECT_NEAR(r60.max_delta, 0.128, 0.005);

  const DiffResult g30 = compareImages(a, grey30, DiffOptions{}, nullptr);
  EXPECT_FALSE(g30.pass);
  EXPECT_EQ(g30.differing, 40 * 40);

  const DiffResult r30 = compareImages(a, red30, DiffOptions{}, nullptr);
  EXPECT_NEAR(r30.max_delta, 0.064, 0.003);
  EXPECT_EQ(r30.differing, 0);  // under the default threshold...
  DiffOptions tight;
  tight.threshold = 0.05;
  const DiffResult r30t = compareImages(a, red30, tight, nullptr);
  EXPECT_FALSE(r30t.pass);  // ...caught with t = 0.05
  EXPECT_EQ(r30t.differing, 40 * 40);
}

TEST(ImageDiff, MissingObjectFails) {
  const Image a = scene(0, 0, true), b = scene(0, 0, false);
  const DiffResult r = compareImages(a, b, DiffOptions{}, nullptr);
  EXPECT_FALSE(r.pass);
  EXPECT_GT(r.differing, 140 * 8 / 2);  // the bar's interior counts, not just its edges
  EXPECT_GT(r.max_delta, 0.5);
}

TEST(ImageDiff, SmallObjectMovedSeveralPixelsFails) {
  // A 5 px-radius disc (a ball) moved 6 px: a real change, not anti-aliasing.
  Image a(128, 128, kBackground.r, kBackground.g, kBackground.b);
  Image b = a;
  drawDisc(a, 60.4, 60.2, 5.0, kDark);
  drawDisc(b, 66.4, 60.2, 5.0, kDark);
  const DiffResult r = compareImages(a, b, DiffOptions{}, nullptr);
  EXPECT_FALSE(r.pass) << r.message;
  EXPECT_GT(r.differing, 30);
}

TEST(ImageDiff, DifferentSizesFailCleanly) {
  const Image a = scene(0, 0, true, 160, 120), b = scene(0, 0, true, 161, 120);
  Image diff(3, 3);
  const DiffResult r = compareImages(a, b, DiffOptions{}, &diff);
  EXPECT_FALSE(r.same_size);
  EXPECT_FALSE(r.pass);
  EXPECT_NE(r.message.find("160x120"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("161x120"), std::string::npos) << r.message;
  EXPECT_TRUE(diff.empty());
  EXPECT_FALSE(compareImages(Image{}, a, DiffOptions{}, nullptr).pass);
  Image broken = a;
  broken.rgba.resize(10);  // inconsistent buffer: refused, never read out of bounds
  const DiffResult rb = compareImages(a, broken, DiffOptions{}, nullptr);
  EXPECT_FALSE(rb.pass);
  EXPECT_NE(rb.message.find("inconsistent"), std::string::npos) << rb.message;
}

TEST(ImageDiff, DiffImageIsRedWhereDifferentOverFadedGrey) {
  Image a = scene();
  Image b = a;
  shiftPatch(b, 5, 5, 25, 25, 0, -120, -120);  // a strongly redder square in the background
  DiffOptions o;
  Image diff;
  const DiffResult r = compareImages(a, b, o, &diff);
  ASSERT_EQ(diff.width, a.width);
  ASSERT_EQ(diff.height, a.height);
  EXPECT_EQ(r.differing, 20 * 20);
  for (int y = 5; y < 25; ++y)
    for (int x = 5; x < 25; ++x) {
      const uint8_t* p = at(diff, x, y);
      ASSERT_TRUE(p[0] == 255 && p[1] == 0 && p[2] == 0) << "pixel " << x << "," << y << " not red";
    }
  // Elsewhere: grey, faded towards white (fade 0.1 keeps 10% of the luma's distance from white).
  const uint8_t* bg = at(diff, 100, 10);
  EXPECT_EQ(bg[0], bg[1]);
  EXPECT_EQ(bg[1], bg[2]);
  EXPECT_GT(bg[0], 240);
  const uint8_t* disc = at(diff, 55, 50);  // inside the orange disc: a bit darker grey
  EXPECT_EQ(disc[0], disc[2]);
  EXPECT_LT(disc[0], bg[0]);
  EXPECT_GT(disc[0], 200);
  // fade = 1 gives the full-strength luma.
  o.fade = 1.0;
  compareImages(a, b, o, &diff);
  EXPECT_LT(at(diff, 55, 50)[0], 200);
}

TEST(ImageDiff, OptionValidationNamesFieldAndRange) {
  DiffOptions o;
  EXPECT_EQ(validateDiffOptions(o), "");
  o.threshold = 1.5;
  EXPECT_NE(validateDiffOptions(o).find("threshold must be in [0, 1]"), std::string::npos);
  o = DiffOptions{};
  o.max_diff_share = -0.1;
  EXPECT_NE(validateDiffOptions(o).find("max_diff_share"), std::string::npos);
  o = DiffOptions{};
  o.fade = std::nan("");
  EXPECT_NE(validateDiffOptions(o).find("fade"), std::string::npos);
}

TEST(ImageDiff, PngRoundTripIsAtomicAndLossless) {
  const std::filesystem::path dir = std::filesystem::path(PONYHOP_TEST_OUT) / "image_diff";
  std::filesystem::create_directories(dir);
  const Image a = scene();
  const std::string path = (dir / "roundtrip.png").string();
  std::string err;
  ASSERT_TRUE(savePng(path, a, &err)) << err;
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const Image b = loadPng(path, &err);
  ASSERT_EQ(b.width, a.width);
  ASSERT_EQ(b.height, a.height);
  EXPECT_EQ(b.rgba, a.rgba);
  const Image missing = loadPng((dir / "nope.png").string(), &err);
  EXPECT_TRUE(missing.empty());
  EXPECT_NE(err.find("nope.png"), std::string::npos) << err;
}

// ---- the executable ----

testing::RunResult runExe(const std::string& args) { return testing::runPonyhop(args, "image_diff_cli"); }

// A PNG whose header declares WxH, with a tiny (wrong) image body: enough for the header check.
std::string pngDeclaring(uint32_t w, uint32_t h) {
  std::string ihdr = "IHDR";
  for (uint32_t v : {w, h}) {
    for (int s = 24; s >= 0; s -= 8) ihdr.push_back(char((v >> s) & 0xff));
  }
  ihdr += std::string("\x08\x06\x00\x00\x00", 5);  // 8 bit RGBA
  std::string png = "\x89PNG\r\n\x1a\n";
  png += std::string("\x00\x00\x00\x0d", 4) + ihdr;
  const uLong crc = crc32(0, reinterpret_cast<const Bytef*>(ihdr.data()), uInt(ihdr.size()));
  for (int s = 24; s >= 0; s -= 8) png.push_back(char((crc >> s) & 0xff));
  png += std::string("\x00\x00\x00\x00IEND\xae\x42\x60\x82", 12);
  return png;
}

TEST(ImageHostile, HugeDeclaredSizeIsRefusedBeforeDecoding) {
  std::string err;
  const Image img = decodePng(pngDeclaring(12000, 12000), "huge.png", &err);
  EXPECT_TRUE(img.empty());
  EXPECT_NE(err.find("huge.png: the image declares 12000x12000 pixels; the limit is 16384 per side and 64 megapixels"),
            std::string::npos)
      << err;
  err.clear();
  decodePng(pngDeclaring(20000, 10), "wide.png", &err);
  EXPECT_NE(err.find("20000x10"), std::string::npos) << err;
  // Inside the limits the same header goes on to the decoder (which finds no image data).
  err.clear();
  decodePng(pngDeclaring(64, 64), "small.png", &err);
  EXPECT_EQ(err.find("declares"), std::string::npos) << err;
  EXPECT_NE(err.find("small.png: cannot read as an image"), std::string::npos) << err;
}

TEST(ImageHostile, FifoAndFolderAreRefusedWithoutBlocking) {
  const std::filesystem::path dir = std::filesystem::path(PONYHOP_TEST_OUT) / "image_hostile";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string fifo = (dir / "fifo.png").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::string err;
  EXPECT_TRUE(loadPng(fifo, &err).empty());
  EXPECT_NE(err.find("fifo.png: is a FIFO (named pipe), not a PNG file"), std::string::npos) << err;
  EXPECT_TRUE(loadPng(dir.string(), &err).empty());
  EXPECT_NE(err.find("is a folder"), std::string::npos) << err;
}

TEST(ImageDiffCli, ExitCodesAndDiffImage) {
  const std::filesystem::path dir = std::filesystem::path(PONYHOP_TEST_OUT) / "image_diff";
  std::filesystem::create_directories(dir);
  auto file = [&](const char* name) { return (dir / name).string(); };
  auto q = [](const std::string& s) { return "\"" + s + "\""; };
  ASSERT_TRUE(savePng(file("a.png"), scene(), nullptr));
  ASSERT_TRUE(savePng(file("a_aa.png"), scene(0.3, 0.3), nullptr));
  ASSERT_TRUE(savePng(file("nobar.png"), scene(0, 0, false), nullptr));
  ASSERT_TRUE(savePng(file("wide.png"), scene(0, 0, true, 161, 120), nullptr));
  std::filesystem::remove(file("d.png"));
  std::filesystem::remove(file("missing.png"));

  testing::RunResult same = runExe("diff " + q(file("a.png")) + " " + q(file("a.png")));
  EXPECT_EQ(same.code, 0) << same.out;
  EXPECT_NE(same.out.find("PASS"), std::string::npos) << same.out;

  testing::RunResult aa = runExe("diff " + q(file("a.png")) + " " + q(file("a_aa.png")));
  EXPECT_EQ(aa.code, 0) << aa.out;
  testing::RunResult aa_off = runExe("diff --no-aa " + q(file("a.png")) + " " + q(file("a_aa.png")));
  EXPECT_EQ(aa_off.code, 1) << aa_off.out;

  testing::RunResult differ =
      runExe("diff " + q(file("a.png")) + " " + q(file("nobar.png")) + " --out " + q(file("d.png")));
  EXPECT_EQ(differ.code, 1) << differ.out;
  EXPECT_NE(differ.out.find("FAIL"), std::string::npos) << differ.out;
  EXPECT_NE(differ.out.find("differing pixels"), std::string::npos) << differ.out;
  EXPECT_NE(differ.out.find("largest difference"), std::string::npos) << differ.out;
  EXPECT_NE(differ.out.find("anti-aliased pixels ignored"), std::string::npos) << differ.out;
  const Image d = loadPng(file("d.png"));
  EXPECT_EQ(d.width, 160);
  EXPECT_EQ(d.height, 120);

  // A generous tolerance turns the same pair into a pass.
  testing::RunResult lenient = runExe("diff " + q(file("a.png")) + " " + q(file("nobar.png")) + " --max-share 0.2");
  EXPECT_EQ(lenient.code, 0) << lenient.out;

  testing::RunResult sizes = runExe("diff " + q(file("a.png")) + " " + q(file("wide.png")));
  EXPECT_EQ(sizes.code, 1) << sizes.out;
  EXPECT_NE(sizes.out.find("161x120"), std::string::npos) << sizes.out;

  testing::RunResult missing = runExe("diff " + q(file("a.png")) + " " + q(file("missing.png")));
  EXPECT_EQ(missing.code, 2) << missing.out;
  EXPECT_NE(missing.out.find("missing.png"), std::string::npos) << missing.out;

  std::ofstream(file("junk.png")) << "not a png";
  testing::RunResult junk = runExe("diff " + q(file("junk.png")) + " " + q(file("a.png")));
  EXPECT_EQ(junk.code, 2) << junk.out;
  EXPECT_NE(junk.out.find("junk.png"), std::string::npos) << junk.out;

  testing::RunResult bad = runExe("diff " + q(file("a.png")) + " " + q(file("a.png")) + " --threshold 1.5");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--threshold"), std::string::npos) << bad.out;
  EXPECT_NE(bad.out.find("[0, 1]"), std::string::npos) << bad.out;
}

}  // namespace
}  // namespace ponyhop

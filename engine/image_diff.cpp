// Model (after pixelmatch's published description; the code is our own):
//  - Colours are alpha-blended over white, then converted to YIQ (NTSC luma + two chroma axes).
//    The distance is d = 0.5053 dY^2 + 0.299 dI^2 + 0.1957 dQ^2 (weights from Kotsarenko and
//    Ramos, "Measuring perceived color difference using YIQ NTSC transmission color space").
//    Its largest value, red against cyan, is 35215; a pixel differs when d > 35215 t^2.
//  - A differing pixel is anti-aliasing when, in either image, it lies on an edge: among its 8
//    neighbours some are darker and some brighter (by luma), it is not itself in a flat patch
//    (at most 2 identical neighbours), and the darkest or the brightest neighbour sits in a flat
//    patch (>= 3 identical neighbours) in BOTH images - i.e. the pixel is a blend between two
//    solid areas that exist in both pictures, so only the sub-pixel coverage changed.
#include "engine/image_diff.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace ponyhop {
namespace {

// Channel value of `c` with opacity `a` (0..1) composited over white.
inline double overWhite(uint8_t c, double a) { return 255.0 + (c - 255.0) * a; }

struct Yiq {
  double y, i, q;
};

inline Yiq toYiq(const uint8_t* p) {
  const double a = p[3] / 255.0;
  const double r = overWhite(p[0], a), g = overWhite(p[1], a), b = overWhite(p[2], a);
  return {0.29889531 * r + 0.58662247 * g + 0.11448223 * b, 0.59597799 * r - 0.27417610 * g - 0.32180189 * b,
          0.21147017 * r - 0.52261711 * g + 0.31114694 * b};
}

inline double luma(const uint8_t* p) { return toYiq(p).y; }

inline bool samePixel(const uint8_t* a, const uint8_t* b) { return std::memcmp(a, b, 4) == 0; }

// True when pixel (x, y) of `img` has >= 3 identical neighbours, i.e. sits in a flat patch.
// At the border, where some neighbours are missing, the outside counts as one identical
// neighbour so that a flat area touching the border still qualifies.
bool inFlatPatch(const Image& img, int x, int y) {
  const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, img.width - 1);
  const int y0 = std::max(y - 1, 0), y1 = std::min(y + 1, img.height - 1);
  int equal = (x0 == x || x1 == x || y0 == y || y1 == y) ? 1 : 0;
  const uint8_t* c = img.px(x, y);
  for (int ny = y0; ny <= y1; ++ny) {
    for (int nx = x0; nx <= x1; ++nx) {
      if ((nx == x && ny == y) || !samePixel(c, img.px(nx, ny))) continue;
      if (++equal >= 3) return true;
    }
  }
  return false;
}

// True when pixel (x, y) of `img` looks like anti-aliasing of an edge between two flat areas
// that are flat in `other` as well (the rule described at the top of the file).
bool looksAntialiased(const Image& img, const Image& other, int x, int y) {
  const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, img.width - 1);
  const int y0 = std::max(y - 1, 0), y1 = std::min(y + 1, img.height - 1);
  int equal = (x0 == x || x1 == x || y0 == y || y1 == y) ? 1 : 0;
  const uint8_t* c = img.px(x, y);
  const double yc = luma(c);
  double darkest = 0, brightest = 0;  // largest luma drop / rise towards a neighbour
  int dx = -1, dy = -1, bx = -1, by = -1;
  for (int ny = y0; ny <= y1; ++ny) {
    for (int nx = x0; nx <= x1; ++nx) {
      if (nx == x && ny == y) continue;
      const uint8_t* n = img.px(nx, ny);
      if (samePixel(c, n)) {
        if (++equal > 2) return false;  // the pixel itself is in a flat patch: a real change
        continue;
      }
      const double drop = yc - luma(n);  // > 0: neighbour darker
      if (drop > darkest) {
        darkest = drop;
        dx = nx;
        dy = ny;
      } else if (-drop > brightest) {
        brightest = -drop;
        bx = nx;
        by = ny;
      }
    }
  }
  if (dx < 0 || bx < 0) return false;  // no darker or no brighter neighbour: not between two areas
  return (inFlatPatch(img, dx, dy) && inFlatPatch(other, dx, dy)) ||
         (inFlatPatch(img, bx, by) && inFlatPatch(other, bx, by));
}

inline void put(Image& img, int x, int y, uint8_t r, uint8_t g, uint8_t b) {
  uint8_t* p = img.px(x, y);
  p[0] = r;
  p[1] = g;
  p[2] = b;
  p[3] = 255;
}

// Grey of the expected pixel's luma, faded towards white by `fade` (1 = full strength).
inline void putFaded(Image& img, int x, int y, const uint8_t* expected, double fade) {
  const double v = std::clamp(255.0 + (luma(expected) - 255.0) * fade, 0.0, 255.0);
  const auto g = static_cast<uint8_t>(std::lround(v));
  put(img, x, y, g, g, g);
}

std::string sizeText(const Image& img) { return std::to_string(img.width) + "x" + std::to_string(img.height); }

}  // namespace

double yiqDelta(const uint8_t* a, const uint8_t* b) {
  const Yiq p = toYiq(a), q = toYiq(b);
  const double dy = p.y - q.y, di = p.i - q.i, dq = p.q - q.q;
  return 0.5053 * dy * dy + 0.299 * di * di + 0.1957 * dq * dq;
}

std::string validateDiffOptions(const DiffOptions& o) {
  auto inUnit = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; };
  if (!inUnit(o.threshold)) return "threshold must be in [0, 1] (got " + std::to_string(o.threshold) + ")";
  if (!inUnit(o.max_diff_share))
    return "max_diff_share must be in [0, 1] (got " + std::to_string(o.max_diff_share) + ")";
  if (!inUnit(o.fade)) return "fade must be in [0, 1] (got " + std::to_string(o.fade) + ")";
  return "";
}

DiffResult compareImages(const Image& expected, const Image& actual, const DiffOptions& options, Image* diff_out) {
  DiffResult r;
  if (expected.width != actual.width || expected.height != actual.height) {
    r.same_size = false;
    r.pass = false;
    r.message = "sizes differ: expected " + sizeText(expected) + ", actual " + sizeText(actual);
    if (diff_out) *diff_out = Image{};
    return r;
  }
  const int w = expected.width, h = expected.height;
  const size_t bytes = static_cast<size_t>(std::max(w, 0)) * static_cast<size_t>(std::max(h, 0)) * 4;
  if (expected.rgba.size() != bytes || actual.rgba.size() != bytes) {
    r.message = "inconsistent image: " + sizeText(expected) + " needs " + std::to_string(bytes) + " bytes, got " +
                std::to_string(expected.rgba.size()) + " (expected) and " + std::to_string(actual.rgba.size()) +
                " (actual)";
    if (diff_out) *diff_out = Image{};
    return r;  // same_size stays false: nothing was compared
  }
  r.same_size = true;
  r.pixels = static_cast<long>(w) * h;
  if (diff_out) *diff_out = Image(w, h, 255, 255, 255, 255);
  const double limit = kMaxYiqDelta * options.threshold * options.threshold;
  double worst = 0;  // largest d over the pixels that count

  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t* e = expected.px(x, y);
      const uint8_t* a = actual.px(x, y);
      const double d = samePixel(e, a) ? 0.0 : yiqDelta(e, a);
      if (d > limit) {
        if (options.detect_antialiasing &&
            (looksAntialiased(expected, actual, x, y) || looksAntialiased(actual, expected, x, y))) {
          ++r.antialiased;
          if (diff_out) put(*diff_out, x, y, 255, 255, 0);
          continue;
        }
        ++r.differing;
        if (diff_out) put(*diff_out, x, y, 255, 0, 0);
      } else if (diff_out) {
        putFaded(*diff_out, x, y, e, options.fade);
      }
      worst = std::max(worst, d);
    }
  }

  r.max_delta = std::min(1.0, std::sqrt(worst / kMaxYiqDelta));
  r.share = r.pixels > 0 ? static_cast<double>(r.differing) / static_cast<double>(r.pixels) : 0.0;
  r.pass = r.share <= options.max_diff_share;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%ld of %ld pixels differ (%.4f%%, allowed %.4f%%)", r.differing, r.pixels,
                100.0 * r.share, 100.0 * options.max_diff_share);
  r.message = buf;
  return r;
}

}  // namespace ponyhop

// Perceptual comparison of two RGBA images for snapshot tests (the model of pixelmatch,
// reimplemented here): per-pixel colour distance in YIQ, anti-aliased pixels detected and
// ignored, a pass/fail verdict on the share of differing pixels, and a diff picture.
// See docs/SNAPSHOTS.md for the model and how to read the output.
#pragma once

#include <string>

#include "engine/image.h"
#include "physics/reflect.h"

namespace ponyhop {

// The largest YIQ distance between two colours (pure red against cyan): the scale of
// DiffOptions::threshold and DiffResult::max_delta.
inline constexpr double kMaxYiqDelta = 35215.0;

struct DiffOptions {
  // Per-pixel colour threshold t in [0, 1] (pixelmatch's t): a pixel differs when its YIQ
  // distance exceeds kMaxYiqDelta * t^2, i.e. when its normalized distance sqrt(d / 35215) > t.
  // 0.1 ignores +-2 noise and also a pure red shift of up to ~46/255 on its own (red weighs
  // little in luma); a grey/luma shift of ~30/255 is caught.
  double threshold = 0.1;
  // Ignore pixels that look like anti-aliasing of an edge in either image (drawn yellow).
  bool detect_antialiasing = true;
  // Share of the image's pixels in [0, 1] allowed to differ before the comparison fails.
  double max_diff_share = 0.001;
  // Intensity of the expected image in the diff picture, [0, 1]: 0 = white background,
  // 1 = full-strength grey copy.
  double fade = 0.1;

  template <class V>
  void reflect(V& v) {
    v("threshold", threshold,
      {.min = 0, .max = 1, .help = "Per-pixel YIQ colour threshold (pixelmatch's t): differs when sqrt(d/35215) > t"});
    v("detect_antialiasing", detect_antialiasing,
      {.help = "Ignore anti-aliased edge pixels (drawn yellow in the diff image)"});
    v("max_diff_share", max_diff_share,
      {.min = 0, .max = 1, .help = "Share of pixels allowed to differ before the comparison fails", .log = true});
    v("fade", fade, {.min = 0, .max = 1, .help = "Strength of the grey copy of the expected image in the diff image"});
  }
};

// "" when every field is in range; otherwise a message naming the field and its allowed range.
std::string validateDiffOptions(const DiffOptions& options);

struct DiffResult {
  bool same_size = false;
  long pixels = 0;       // width * height (0 when the sizes differ)
  long differing = 0;    // pixels over the threshold and not anti-aliasing
  double share = 0;      // differing / pixels
  double max_delta = 0;  // normalized YIQ distance sqrt(d / 35215) in [0, 1] of the worst
                         // pixel that is not anti-aliasing; compare with DiffOptions::threshold
  long antialiased = 0;  // pixels over the threshold but ignored as anti-aliasing
  bool pass = false;     // same_size && share <= max_diff_share
  std::string message;   // one line: why it failed (sizes, share) or a summary on pass
};

// Compares `actual` against `expected`. Different sizes fail (same_size = false, message naming
// both sizes) and leave `diff_out` empty. Otherwise, when `diff_out` is given, it receives an
// image of the same size: a faded grey copy of `expected`, differing pixels red, ignored
// anti-aliased pixels yellow. Options are assumed valid (see validateDiffOptions).
DiffResult compareImages(const Image& expected, const Image& actual, const DiffOptions& options,
                         Image* diff_out = nullptr);

// Squared YIQ distance d in [0, 35215] of two RGBA pixels, each alpha-blended over white first.
double yiqDelta(const uint8_t* a, const uint8_t* b);

}  // namespace ponyhop

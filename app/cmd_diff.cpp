// `ponyhop diff EXPECTED.png ACTUAL.png`: the snapshot comparator on the command line.
// Exit codes: 0 pass, 1 differ beyond tolerance or different sizes, 2 a file could not be read
// or the diff image could not be written. Bad option values are CLI11 usage errors.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/output_safety.h"
#include "app/scene_args.h"
#include "engine/image_diff.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

struct DiffArgs {
  std::string expected, actual, out;
  DiffOptions options;
  bool no_aa = false;
};

// A CLI11 check that names the allowed range (CLI11 prefixes the option's name).
CLI::Validator unitRange(const std::string& what) {
  return CLI::Validator(
      [what](std::string& s) -> std::string {
        double v = 0;
        try {
          size_t used = 0;
          v = std::stod(s, &used);
          if (used != s.size()) throw std::invalid_argument(s);
        } catch (const std::exception&) {
          return "'" + s + "' is not a number; " + what + " must be in [0, 1]";
        }
        if (!(v >= 0.0 && v <= 1.0)) return s + " is out of range; " + what + " must be in [0, 1]";
        return "";
      },
      "in [0, 1]");
}

int runDiff(const DiffArgs& args) {
  std::string err;
  if (!args.out.empty()) {
    // Before reading anything: never the golden, never a device, a folder that takes the file.
    checkOutputFile("--out", args.out, {args.expected, args.actual});
  }
  const Image expected = loadPng(args.expected, &err);
  if (expected.empty()) {
    std::fprintf(stderr, "ponyhop diff: expected image %s\n", err.c_str());
    return 2;
  }
  const Image actual = loadPng(args.actual, &err);
  if (actual.empty()) {
    std::fprintf(stderr, "ponyhop diff: actual image %s\n", err.c_str());
    return 2;
  }
  DiffOptions options = args.options;
  options.detect_antialiasing = !args.no_aa;
  if (const std::string bad = validateDiffOptions(options); !bad.empty()) {
    std::fprintf(stderr, "ponyhop diff: %s\n", bad.c_str());
    return 2;
  }

  Image diff;
  const DiffResult r = compareImages(expected, actual, options, args.out.empty() ? nullptr : &diff);
  std::printf("expected: %s (%dx%d)\n", args.expected.c_str(), expected.width, expected.height);
  std::printf("actual:   %s (%dx%d)\n", args.actual.c_str(), actual.width, actual.height);
  if (!r.same_size) {
    std::printf("FAIL: %s\n", r.message.c_str());
    if (!args.out.empty()) std::printf("no diff image written (sizes differ)\n");
    return 1;
  }
  std::printf("differing pixels: %ld of %ld (%.4f%%; allowed %.4f%%, --max-share %g)\n", r.differing, r.pixels,
              100.0 * r.share, 100.0 * options.max_diff_share, options.max_diff_share);
  std::printf("largest difference: %.4f (normalized YIQ 0..1; per-pixel --threshold %g)\n", r.max_delta,
              options.threshold);
  if (options.detect_antialiasing)
    std::printf("anti-aliased pixels ignored: %ld\n", r.antialiased);
  else
    std::printf("anti-aliased pixels ignored: none (--no-aa)\n");
  if (!args.out.empty()) {
    if (!savePng(args.out, diff, &err)) {
      std::fprintf(stderr, "ponyhop diff: diff image %s\n", err.c_str());
      return 2;
    }
    std::printf("diff image: %s (red: differs, yellow: anti-aliasing ignored)\n", args.out.c_str());
  }
  std::printf("%s\n", r.pass ? "PASS" : "FAIL");
  return r.pass ? 0 : 1;
}

}  // namespace

void addDiffCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<DiffArgs>();
  CLI::App* cmd = app.add_subcommand("diff",
                                     "Compare two PNGs perceptually (YIQ distance, anti-aliasing ignored). "
                                     "Exit 0 pass, 1 differ or sizes differ, 2 unreadable file.");
  cmd->add_option("expected", args->expected, "Expected (golden) PNG")->required();
  cmd->add_option("actual", args->actual, "Actual PNG")->required();
  cmd->add_option("--out", args->out, "Write the diff image here (red: differs, yellow: anti-aliasing)")
      ->check(nonEmpty());
  cmd->add_option("--threshold", args->options.threshold,
                  "Per-pixel colour threshold t in [0, 1]: a pixel differs when its YIQ distance > 35215 t^2")
      ->check(unitRange("--threshold"))
      ->capture_default_str();
  cmd->add_option("--max-share", args->options.max_diff_share,
                  "Share of pixels in [0, 1] allowed to differ before failing")
      ->check(unitRange("--max-share"))
      ->capture_default_str();
  cmd->add_option("--fade", args->options.fade, "Strength in [0, 1] of the grey copy of EXPECTED in the diff image")
      ->check(unitRange("--fade"))
      ->capture_default_str();
  cmd->add_flag("--no-aa", args->no_aa, "Count anti-aliased pixels as differences too");
  cmd->callback([args, &exit_code] { exit_code = runCommand("diff", [&] { return runDiff(*args); }); });
}

}  // namespace ponyhop

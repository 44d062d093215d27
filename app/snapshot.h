// Snapshot tests of scenes from a shot list: `ponyhop snapshot SHOTS.txt` renders each shot,
// compares it with its golden PNG (engine/image_diff.h) and checks that the shot's subject is
// actually in the picture. The project's own goldens (tests/snapshots/shots.txt) run through the
// same code. Format and workflow: docs/SNAPSHOTS.md.
//
// A shot list is plain text, one shot per line; `#` starts a comment:
//
//   # name        scene                        options (key=value; a key with a dot is a --set)
//   defaults      size=320x180 light.shadow_size=1024
//   chain_swing   assets/scenes/chain.json     t=0.45 subject=chain
//   hopper_high   assets/scenes/hopper.json    t=2 wait=flight threshold=0.05 camera.fov=40
//
// A `defaults` line sets options for the shots after it.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "engine/image.h"
#include "engine/image_diff.h"
#include "sim/scene.h"

namespace ponyhop {

struct Shot {
  std::string name;               // the golden is GOLDEN_DIR/NAME.png
  std::string scene;              // as written in the list
  std::string scene_path;         // resolved (working directory, then the list's folder, then the repository)
  double t = 0.0;                 // s, the moment rendered
  int width = 0, height = 0;      // px; 0: the scene's render.width/height
  std::vector<std::string> sets;  // scene overrides key=value, as `--set`
  DiffOptions diff;               // threshold, max_share
  // Hopper scenes: from t on, step to the first moment in stance at the bottom of the bounce
  // ("stance") or in flight just past the apex ("flight"), at most 3 s. "": render at t.
  std::string wait;
  bool panel = false;  // ui=panel: the tuning panel beside the scene, as `ponyhop render --ui`
  // Parts that must be visible: "head", "chain", "hopper" (SceneDraw::Part). Empty: every part
  // the scene has, together. subject=none turns the check off.
  std::vector<std::string> subject;
  bool check_subject = true;
  double min_subject = 0.002;  // share of the picture each subject must change, 0..1 (0.2 %)
  int line = 0;                // in the list file
};

struct ShotList {
  std::string path;        // the list file
  std::string golden_dir;  // the list's folder unless told otherwise
  std::vector<Shot> shots;
};

// Reads and checks a shot list (names, options, ranges) and loads every scene with its
// overrides, so that nothing is rendered or written when any shot is wrong. Throws InputError
// naming the file, the line, the key and what is allowed.
ShotList loadShotList(const std::string& path, const std::string& golden_dir = "");

// The scene of a shot: the file, the shot's size and overrides, validated. Throws InputError.
Scene shotScene(const Shot& shot);

struct ShotPicture {
  Image image;
  double t = 0.0;        // the moment rendered (after `wait`)
  std::string renderer;  // GL renderer and version
  std::string problem;   // non-empty when the shot could not be rendered as asked
  // Share of the picture each subject changes (drawn against not drawn), in Shot::subject order
  // (one entry for the default "everything"; none for subject=none or ui=panel).
  std::vector<std::pair<std::string, double>> coverage;
};

// Renders a shot headless (and its subject coverage). Throws InputError / std::runtime_error.
ShotPicture renderShot(const Shot& shot);

// "" when every subject covers at least min_subject; otherwise why not (names the subject and share).
std::string subjectProblem(const Shot& shot, const ShotPicture& picture);

// expected | actual | diff side by side on a dark strip (a missing part stays dark).
Image composeComparison(const Image& expected, const Image& actual, const Image& diff);

struct SnapshotOptions {
  bool update = false;                   // rewrite the goldens on purpose
  bool ci = false;                       // CI=true: no goldens written at all; a missing golden fails
  std::string out_dir = "snapshot-out";  // actual and expected|actual|diff pictures of failures
  std::vector<std::string> only;         // shot names; empty: all
};

// True when the environment variable CI is set to something other than "", "0" or "false".
bool inCi();

// Runs the shots; prints one line per shot and a summary to `out`, problems to `err`.
// Returns 0 all pass (new goldens written outside CI count as passing), 1 a shot differs, lacks
// its subject, cannot be simulated, or has no golden under CI; 2 a golden or picture cannot be
// written or read, or --update under CI.
int runSnapshots(const ShotList& list, const SnapshotOptions& options, std::FILE* out, std::FILE* err);

}  // namespace ponyhop

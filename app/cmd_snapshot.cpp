// `ponyhop snapshot SHOTS.txt`: snapshot tests of scenes (app/snapshot.h, docs/SNAPSHOTS.md).
// Exit codes as `ponyhop diff`: 0 every shot passes, 1 a shot differs or misses its subject or
// golden (under CI), 2 a bad shot list, scene or option, or a file that cannot be read or written.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "app/snapshot.h"
#include "sim/scene_io.h"

namespace ponyhop {

namespace {

struct SnapshotArgs {
  std::string list;
  std::string goldens;
  SnapshotOptions options;
};

int runSnapshotCommand(const SnapshotArgs& args) {
  const ShotList list = loadShotList(args.list, args.goldens);
  SnapshotOptions options = args.options;
  options.ci = inCi();
  return runSnapshots(list, options, stdout, stderr);
}

}  // namespace

void addSnapshotCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<SnapshotArgs>();
  CLI::App* cmd = app.add_subcommand(
      "snapshot",
      "Render the shots of a shot list and compare them with their goldens (GOLDENS/NAME.png). A missing "
      "golden is written (a failure under CI=true); a failure writes expected | actual | diff into --out. "
      "Exit 0 pass, 1 a shot fails, 2 bad input.");
  cmd->add_option("shots", args->list,
                  "Shot list: one shot per line, NAME SCENE.json [t=S size=WxH threshold=T key.field=V ...]")
      ->required();
  cmd->add_option("--goldens", args->goldens, "Folder of the golden PNGs (default: the shot list's folder)");
  cmd->add_option("--out", args->options.out_dir, "Where failures write NAME.actual.png and NAME.compare.png")
      ->capture_default_str();
  cmd->add_flag("--update", args->options.update, "Rewrite the goldens on purpose (refused under CI=true)");
  cmd->add_option("--only", args->options.only, "Only these shots (repeatable)")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->callback([args, &exit_code] { exit_code = runCommand("snapshot", [&] { return runSnapshotCommand(*args); }); });
}

}  // namespace ponyhop

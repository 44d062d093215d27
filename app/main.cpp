// ponyhop: constrained rigid-body dynamics the way games use it (a ponytail on a keyframed head,
// a Raibert hopper), rendered headless to PNG/video, tuned live in a window, guarded by snapshots.
#include <csignal>
#include <cstdio>
#include <exception>

#include "app/commands.h"
#include "bench/commands.h"
#include "sim/data_dir.h"

int main(int argc, char** argv) {
  // A file size limit (RLIMIT_FSIZE) makes a write fail with EFBIG, reported like a full disk,
  // instead of killing the process with SIGXFSZ halfway through a file.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"ponyhop: a ponytail and a Raibert hopper, simulated with Lagrange multipliers"};
  app.set_version_flag("--version", std::string("ponyhop ") + ponyhop::versionString());
  app.require_subcommand(1);
  int exit_code = 0;
  ponyhop::addDiffCommand(app, exit_code);
  ponyhop::addSnapshotCommand(app, exit_code);
  ponyhop::addSceneDocCommand(app, exit_code);
  ponyhop::addRenderCommand(app, exit_code);
  ponyhop::addSimCommand(app, exit_code);
  ponyhop::addExportCommand(app, exit_code);
  ponyhop::addVideoCommand(app, exit_code);
  ponyhop::addSolveCommand(app, exit_code);
  ponyhop::addBenchCommand(app, exit_code);
  ponyhop::addBenchRenderCommand(app, exit_code);
#ifdef PONYHOP_WINDOW
  ponyhop::addRunCommand(app, exit_code);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message; its own codes (105 for a value out of range, 106 for a missing
    // option...) become the one usage-error code every command documents: 2 (0 for --help).
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ponyhop: %s\n", e.what());
    return 1;
  }
  return exit_code;
}

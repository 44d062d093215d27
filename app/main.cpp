// ponyhop: constrained rigid-body dynamics the way games use it (a ponytail on a keyframed head,
// a Raibert hopper), rendered headless to PNG/video, tuned live in a window, guarded by snapshots.
#include <cstdio>
#include <exception>

#include "app/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"ponyhop: a ponytail and a Raibert hopper, simulated with Lagrange multipliers"};
  app.require_subcommand(1);
  int exit_code = 0;
  ponyhop::addDiffCommand(app, exit_code);
  ponyhop::addSceneDocCommand(app, exit_code);
  ponyhop::addRenderCommand(app, exit_code);
  ponyhop::addSimCommand(app, exit_code);
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

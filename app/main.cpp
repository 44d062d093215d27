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
#ifdef PONYHOP_WINDOW
  ponyhop::addRunCommand(app, exit_code);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ponyhop: %s\n", e.what());
    return 1;
  }
  return exit_code;
}

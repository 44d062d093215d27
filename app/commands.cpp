#include "app/commands.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "sim/data_dir.h"
#include "sim/input_error.h"

namespace ponyhop {

int runCommand(const char* name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::fprintf(stderr, "ponyhop %s: %s\n", name, e.what());
    return 2;
  }
}

int runCommandLine(int argc, char** argv, const std::function<void(CLI::App&, int&)>& add_more) {
  CLI::App app{"ponyhop: a ponytail and a Raibert hopper, simulated with Lagrange multipliers"};
  app.set_version_flag("--version", std::string("ponyhop ") + versionString());
  app.require_subcommand(1);
  int exit_code = 0;
  addDiffCommand(app, exit_code);
  addSnapshotCommand(app, exit_code);
  addSceneDocCommand(app, exit_code);
  addRenderCommand(app, exit_code);
  addSimCommand(app, exit_code);
  addExportCommand(app, exit_code);
  addVideoCommand(app, exit_code);
  addSolveCommand(app, exit_code);
  if (add_more) add_more(app, exit_code);
#ifdef PONYHOP_WINDOW
  addRunCommand(app, exit_code);
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

}  // namespace ponyhop

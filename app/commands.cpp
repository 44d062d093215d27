#include "app/commands.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

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

namespace {

// A CommandSpec's subcommand, as app/cmd_*.cpp add theirs.
void addSpecCommand(CLI::App& app, const CommandSpec& spec, int& exit_code) {
  auto* cmd = app.add_subcommand(spec.name, spec.help);
  for (const CommandOption& o : spec.options) {
    std::visit(
        [&](auto* target) {
          using T = std::remove_pointer_t<decltype(target)>;
          if constexpr (std::is_same_v<T, bool>) {
            cmd->add_flag(o.name, *target, o.help);
          } else {
            CLI::Option* option = cmd->add_option(o.name, *target, o.help);
            if (o.comma_list) option->delimiter(',');
            if constexpr (std::is_same_v<T, int> || std::is_same_v<T, std::vector<int>>) {
              if (o.range) option->check(CLI::Range(int(o.range->first), int(o.range->second)));
            } else if (o.range) {
              option->check(CLI::Range(o.range->first, o.range->second));
            }
            if (!o.members.empty()) option->check(CLI::IsMember(o.members));
          }
        },
        o.target);
  }
  cmd->callback([&spec, &exit_code] { exit_code = spec.run(); });
}

}  // namespace

int runCommandLine(int argc, char** argv, const std::vector<CommandSpec>& more) {
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
  for (const CommandSpec& spec : more) addSpecCommand(app, spec, exit_code);
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

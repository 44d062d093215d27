// Subcommands of the `ponyhop` executable, one file each (app/cmd_*.cpp; the bench's: bench/commands.h).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

// Only references to CLI11's App here: a file that includes <CLI/CLI.hpp> compiles all of CLI11
// (its namespace-scope validators and the virtual functions of App, Formatter and Config: about
// 4.5 s of GCC's time per translation unit), so only the files that build the command line include it.
namespace CLI {
class App;
}  // namespace CLI

namespace ponyhop {

// Each adds its subcommand to `app`; the subcommand's callback runs it and sets `exit_code`.
void addDiffCommand(CLI::App& app, int& exit_code);
void addSnapshotCommand(CLI::App& app, int& exit_code);  // app/cmd_snapshot.cpp: shot lists against goldens
void addSceneDocCommand(CLI::App& app, int& exit_code);
void addRenderCommand(CLI::App& app, int& exit_code);
void addSimCommand(CLI::App& app, int& exit_code);
void addExportCommand(CLI::App& app, int& exit_code);  // app/cmd_export.cpp: a glTF bake
void addVideoCommand(CLI::App& app, int& exit_code);   // app/cmd_video.cpp: frames -> video
void addSolveCommand(CLI::App& app, int& exit_code);   // app/cmd_solve.cpp: the goal solve
#ifdef PONYHOP_WINDOW
void addRunCommand(CLI::App& app, int& exit_code);  // app/cmd_run.cpp: the window with the tuning panel
#endif

// A command's body run as every command runs it: bad input (an InputError: a scene, an option, a
// path) is printed as "ponyhop NAME: message" and gives exit code 2; otherwise the body's code.
int runCommand(const char* name, const std::function<int()>& body);

// One option of a subcommand described without CLI11 (CommandSpec). A bool is a flag ("--quick"
// sets it, "!--no-hopper" clears it); the other targets take a value.
struct CommandOption {
  using Target = std::variant<bool*, int*, double*, std::string*, std::vector<int>*, std::vector<double>*,
                              std::vector<std::string>*>;
  std::string name;
  Target target;
  std::string help;
  bool comma_list = false;                         // a list given as A,B,C
  std::optional<std::pair<double, double>> range;  // the values allowed (as integers for int targets)
  std::vector<std::string> members;                // the values allowed; empty: any

  CommandOption& list() {
    comma_list = true;
    return *this;
  }
  CommandOption& within(double lo, double hi) {
    range = {lo, hi};
    return *this;
  }
  CommandOption& oneOf(std::vector<std::string> values) {
    members = std::move(values);
    return *this;
  }
};

// A subcommand described without CLI11, for bench/'s: runCommandLine adds it to the command line
// with CLI11 in app/commands.cpp, so CLI11 (about 4.5 s of GCC's time in every translation unit that
// includes it) is compiled in app/'s batch alone, not in bench/'s too.
struct CommandSpec {
  std::string name, help;
  std::vector<CommandOption> options;  // in the order --help lists them
  std::function<int()> run;            // the command, once its options are parsed: its exit code

  CommandSpec(std::string command, std::string command_help)
      : name(std::move(command)), help(std::move(command_help)) {}
  template <class T>
  CommandOption& add(std::string option, T& target, std::string option_help) {
    CommandOption& o = options.emplace_back();
    o.name = std::move(option);
    o.target = &target;
    o.help = std::move(option_help);
    return o;
  }
};

// The whole command line of `ponyhop`: app/'s subcommands, then `more` (app/main.cpp: the bench's),
// parsed; the exit code (2 for a usage error, 0 for --help). Here rather than in main.cpp so that
// CLI11 is compiled in app/'s batch of command files, not once more there.
int runCommandLine(int argc, char** argv, const std::vector<CommandSpec>& more);

}  // namespace ponyhop

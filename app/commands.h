// Subcommands of the `ponyhop` executable, one file each (app/cmd_*.cpp; the bench's: bench/commands.h).
#pragma once

#include <functional>

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

// The whole command line of `ponyhop`: app/'s subcommands, those `add_more` adds (app/main.cpp:
// the bench's), parsed; the exit code (2 for a usage error, 0 for --help). Here rather than in
// main.cpp so that CLI11 is compiled in app/'s one batch of command files, not once more there.
int runCommandLine(int argc, char** argv, const std::function<void(CLI::App&, int&)>& add_more);

}  // namespace ponyhop

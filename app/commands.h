// Subcommands of the `ponyhop` executable, one file each (app/cmd_*.cpp; the bench's: bench/commands.h).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

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

}  // namespace ponyhop

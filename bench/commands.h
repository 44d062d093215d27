// The bench's subcommands of the `ponyhop` executable (app/main.cpp adds them beside app/commands.h's).
#pragma once

#include <string>
#include <vector>

// Only references to CLI11's App here, as in app/commands.h: the tests that include this header
// do not compile CLI11.
namespace CLI {
class App;
}  // namespace CLI

namespace ponyhop {

// As app/commands.h: each adds its subcommand to `app`; the callback runs it and sets `exit_code`.
void addBenchCommand(CLI::App& app, int& exit_code);        // bench/cmd_bench.cpp: speed against accuracy
void addBenchRenderCommand(CLI::App& app, int& exit_code);  // bench/cmd_bench_render.cpp: render time per pass

// `ponyhop bench-render`'s default scenes: those `make demo` renders (the Makefile's DEMO_SCENES,
// read when the build is configured), in its order, then ponytail_hopper (the hopper with a chain
// on it, not in the demo); as repository-relative paths.
std::vector<std::string> benchRenderDefaultScenes();

}  // namespace ponyhop

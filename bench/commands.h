// The bench's subcommands of the `ponyhop` executable (app/main.cpp adds them beside app/commands.h's).
#pragma once

#include <string>
#include <vector>

#include "app/commands.h"  // CommandSpec: the bench's options, added to the command line by app/ (no CLI11 here)

namespace ponyhop {

// Each describes its subcommand: its options and what it runs (app/main.cpp hands them to
// runCommandLine). Described, not added with CLI11: a file that includes CLI11 compiles all of it.
CommandSpec benchCommand();        // bench/cmd_bench.cpp: speed against accuracy
CommandSpec benchRenderCommand();  // bench/cmd_bench_render.cpp: render time per pass

// `ponyhop bench-render`'s default scenes: those `make demo` renders (the Makefile's DEMO_SCENES,
// read when the build is configured), in its order, then ponytail_hopper (the hopper with a chain
// on it, not in the demo); as repository-relative paths.
std::vector<std::string> benchRenderDefaultScenes();

}  // namespace ponyhop

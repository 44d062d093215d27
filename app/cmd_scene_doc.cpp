// `ponyhop scene-doc`: the reference of every scene field, generated from the reflect() lists so
// that docs/SCENES.md can never disagree with the code.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "app/commands.h"
#include "sim/scene_io.h"

namespace ponyhop {

void addSceneDocCommand(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("scene-doc", "Print the scene file reference (Markdown)");
  cmd->callback([&exit_code] {
    std::fputs(sceneReferenceMarkdown().c_str(), stdout);
    exit_code = 0;
  });
}

}  // namespace ponyhop

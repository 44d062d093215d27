// `ponyhop run SCENE [--frames N] [--screenshot PATH] [--size WxH] [--set key=value]...`: the
// scene in a window with the tuning panel (docs/TUNING.md). Built with the window (PONYHOP_WINDOW).
#ifdef PONYHOP_WINDOW

#include <CLI/CLI.hpp>
#include <cstdio>

#include "app/commands.h"
#include "app/scene_args.h"
#include "app/ui_window.h"
#include "sim/scene_io.h"

namespace ponyhop {

void addRunCommand(CLI::App& app, int& exit_code) {
  struct RunArgs {
    SceneArgs scene;
    WindowOptions window;
    std::string size;
    bool no_vsync = false;
    std::string present = "rects";
  };
  auto args = std::make_shared<RunArgs>();
  auto* cmd = app.add_subcommand("run", "Play a scene in a window with the tuning panel");
  args->scene.add(cmd);
  cmd->add_option("--frames", args->window.frames, "Close after N frames (default: run until closed)")
      ->check(CLI::Range(1, 100000000));
  cmd->add_option("--screenshot", args->window.screenshot, "Write the last frame to this PNG before closing");
  cmd->add_option("--size", args->size, "Window size WIDTHxHEIGHT, scene view + panel (default 1280x720)");
  cmd->add_flag("--no-vsync", args->no_vsync, "Do not wait for the display's refresh (frame-time measurements)");
  cmd->add_option("--quality-log", args->window.quality_log,
                  "Write one line per frame: the scene view's quality (draft/final) and why (tests)");
  cmd->add_option("--draft-scale", args->window.draft_scale,
                  "Resolution of the moving (draft) view per direction, upscaled (default 0.5; 1: full)")
      ->check(CLI::Range(0.25, 1.0));
  cmd->add_option("--present", args->present,
                  "How frames reach the screen: rects (only the rectangles that changed, by "
                  "GLX_MESA_copy_sub_buffer where the GLX has it; else swap) or swap (the whole frame)")
      ->check(CLI::IsMember({"rects", "swap"}));
  cmd->add_option("--idle-wait", args->window.idle_wait,
                  "Seconds a frame after one that changed nothing waits for an event (default 0.1; 0: poll)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->callback([args, &exit_code] {
    exit_code = runCommand("run", [&] {
      const Scene scene = args->scene.load();
      WindowOptions o = args->window;
      o.vsync = !args->no_vsync;
      o.copy_rects = args->present == "rects";
      if (!args->size.empty()) {
        char tail = 0;
        if (std::sscanf(args->size.c_str(), "%dx%d%c", &o.width, &o.height, &tail) != 2 || o.width < 320 ||
            o.height < 200 || o.width > 16384 || o.height > 16384) {
          throw InputError("--size " + args->size + ": expected WIDTHxHEIGHT of at least 320x200, e.g. 1280x720");
        }
      }
      return runWindow(scene, o);
    });
  });
}

}  // namespace ponyhop

#endif  // PONYHOP_WINDOW

// `ponyhop run`: the scene playing in a GLFW window with the tuning panel beside it
// (app/window_app.cpp, built with -DPONYHOP_WINDOW=ON).
#pragma once

#include <string>

#include "sim/scene.h"

namespace ponyhop {

struct WindowOptions {
  int width = 1280, height = 720;  // the window: scene view + panel
  int frames = 0;                  // > 0: close after this many frames (tests, measurements)
  std::string screenshot;          // PNG of the last frame, written before closing
  bool vsync = true;               // swap interval 1 (off when measuring)
  std::string quality_log;         // a line per frame: its number, the view's quality, what moved (tests)
  double draft_scale = 0.5;        // the draft view's resolution per direction (1: the window's)
  // Frames reach the screen by GLX_MESA_copy_sub_buffer where the GLX has it, only the rectangles
  // that changed (false: always a swap of the whole frame, as before session 28).
  bool copy_rects = true;
  // After a frame that changed nothing on the screen, the next one waits up to this long (s) for
  // an event instead of polling (0: poll, spin). The wait is not counted in the frame's time.
  double idle_wait = 0.1;
};

// Runs until the window is closed (or `frames` are shown). Returns the exit code; prints the
// mean frame time and the per-stage times on stderr at the end.
int runWindow(const Scene& scene, const WindowOptions& options);

}  // namespace ponyhop

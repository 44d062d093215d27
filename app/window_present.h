// How the window's back buffer reaches the screen (`ponyhop run`): by a swap, or, where the GLX
// has GLX_MESA_copy_sub_buffer (Mesa's drisw, as under Xvfb), by copying only the rectangles that
// changed, which leaves the back buffer as it was: the compositor then draws only what changed
// into it (UiGl::setTargetKeeps) and an unchanged frame costs nothing (docs/bench/render.md,
// session 28). Kept apart from the rest of the window: it includes X11's and GLX's headers.
#pragma once

struct GLFWwindow;

namespace ponyhop {

class WindowPresenter {
 public:
  // `copy_rects`: use GLX_MESA_copy_sub_buffer where the GLX has it (false: always swap).
  WindowPresenter(GLFWwindow* window, bool copy_rects);
  // Whether rectangles are copied (the back buffer keeps its contents between presents).
  bool copiesRects() const { return copy_ != nullptr; }
  // What `run` prints: how frames are presented and why.
  const char* how() const { return how_; }
  // Pushes the rectangle [x, x + w) x [y, y + h) of the back buffer (GL's window coordinates,
  // origin at the lower left) to the window; the back buffer stays as it is. Needs copiesRects().
  void copyRect(int x, int y, int w, int h) const;
  void swap() const;

 private:
  GLFWwindow* window_ = nullptr;
  void* display_ = nullptr;
  unsigned long drawable_ = 0;
  void (*copy_)() = nullptr;  // glXCopySubBufferMESA, cast back to its type where it is called
  const char* how_ = "";
};

}  // namespace ponyhop

#include "app/window_present.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

// GLFW's native access, as GLFW/glfw3native.h declares it for X11 and GLX (that header pulls in
// Xrandr's and GLX's headers, which the window does not otherwise need): the display, and the
// GLX drawable (an XID) the context draws to.
extern "C" {
struct _XDisplay;
_XDisplay* glfwGetX11Display(void);
unsigned long glfwGetGLXWindow(GLFWwindow* window);
}

namespace ponyhop {

WindowPresenter::WindowPresenter(GLFWwindow* window, bool copy_rects) : window_(window) {
  if (!copy_rects) {
    how_ = "by swapping the whole frame (rectangle copies turned off)";
    return;
  }
  // GLX's extensions, asked through GLFW (no -lGL: engine/gl_context.h); the function by
  // glXGetProcAddress, which GLFW's glfwGetProcAddress is under GLX.
  if (!glfwExtensionSupported("GLX_MESA_copy_sub_buffer")) {
    how_ = "by swapping the whole frame (the GLX has no GLX_MESA_copy_sub_buffer)";
    return;
  }
  _XDisplay* display = glfwGetX11Display();
  const unsigned long drawable = glfwGetGLXWindow(window);
  const GLFWglproc fn = glfwGetProcAddress("glXCopySubBufferMESA");
  if (!display || !drawable || !fn) {
    how_ = "by swapping the whole frame (GLX_MESA_copy_sub_buffer listed but not usable)";
    return;
  }
  display_ = display;
  drawable_ = drawable;
  copy_ = fn;
  how_ = "by GLX_MESA_copy_sub_buffer: only the rectangles that changed, nothing when nothing did";
}

void WindowPresenter::copyRect(int x, int y, int w, int h) const {
  // glXCopySubBufferMESA(Display*, GLXDrawable, x, y, width, height)
  using CopySubBuffer = void (*)(_XDisplay*, unsigned long, int, int, int, int);
  if (copy_ && w > 0 && h > 0)
    reinterpret_cast<CopySubBuffer>(copy_)(static_cast<_XDisplay*>(display_), drawable_, x, y, w, h);
}

void WindowPresenter::swap() const { glfwSwapBuffers(window_); }

}  // namespace ponyhop

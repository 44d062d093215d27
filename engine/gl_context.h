// GL contexts and the GL loader. The renderer never cares where its context comes from: headless
// (OSMesa, here) or a GLFW window (app/), as long as GL 3.3 core is current and loadGL() was
// called with that context's own getProcAddress. We never link -lGL: with -lOSMesa in the same
// program the two libraries' entry points collide (docs/RENDERING.md, "The GL loader story"), so every GL
// call goes through glad's function pointers.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ponyhop {

// Same shape as GLADloadfunc, glfwGetProcAddress and (after a cast) OSMesaGetProcAddress, so the
// window can pass `glfwGetProcAddress` without including glad here.
using GLProc = void (*)();
using GLProcLoader = GLProc (*)(const char* name);

// Loads the GL 3.3 core entry points for the current context. Returns false (with a message) when
// the loader fails or the context is older than 3.3. Call once per process after the first
// context is made current (glad keeps global pointers; contexts of one driver share them).
bool loadGL(GLProcLoader get_proc_address, std::string* err);

// "GL_RENDERER / GL_VERSION" of the current context (recorded beside golden images).
std::string glRendererName();
std::string glVersionString();

// Reads colour attachment 0 of framebuffer `fbo` (width x height RGBA8) into `rgba`, top row first
// (GL's rows run bottom-up, images top-down). Leaves GL_READ_FRAMEBUFFER bound to 0.
void readFramebufferRGBA(unsigned fbo, int width, int height, std::vector<uint8_t>& rgba);

// An offscreen OSMesa context (llvmpipe), GL 3.3+ core profile, no X. Creating it makes it current
// and loads GL. The context's own colour buffer (the "default framebuffer") is width x height RGBA8;
// the renderer draws into its own FBOs and may blit there, but headless code reads the renderer's
// resolve FBO instead.
class HeadlessContext {
 public:
  static std::unique_ptr<HeadlessContext> create(int width, int height, std::string* err);
  ~HeadlessContext();
  HeadlessContext(const HeadlessContext&) = delete;
  HeadlessContext& operator=(const HeadlessContext&) = delete;

  bool makeCurrent();
  int width() const { return width_; }
  int height() const { return height_; }
  std::string rendererName() const;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string version() const;       // GL_VERSION, e.g. "4.5 (Core Profile) Mesa 22.3.6"

 private:
  HeadlessContext() = default;
  void* ctx_ = nullptr;  // OSMesaContext
  int width_ = 0, height_ = 0;
  std::unique_ptr<unsigned char[]> buffer_;
};

}  // namespace ponyhop

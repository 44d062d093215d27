#include "engine/gl_context.h"

#include <cstring>

// glad first: it defines __gl_h_, so the <GL/gl.h> that osmesa.h includes is skipped and every
// GL symbol stays glad's pointer.
// clang-format off
#include <glad/gl.h>
#include <GL/osmesa.h>
// clang-format on

namespace ponyhop {

bool loadGL(GLProcLoader get_proc_address, std::string* err) {
  if (!get_proc_address) {
    if (err) *err = "loadGL: no getProcAddress function given";
    return false;
  }
  const int version = gladLoadGL(reinterpret_cast<GLADloadfunc>(get_proc_address));
  if (version == 0) {
    if (err) *err = "loadGL: glad could not load OpenGL (is a context current?)";
    return false;
  }
  if (GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 33) {
    if (err)
      *err = "loadGL: OpenGL 3.3 core is required, the context offers " + std::to_string(GLAD_VERSION_MAJOR(version)) +
             "." + std::to_string(GLAD_VERSION_MINOR(version));
    return false;
  }
  return true;
}

static std::string glString(GLenum name) {
  if (!glGetString) return "";
  const GLubyte* s = glGetString(name);
  return s ? reinterpret_cast<const char*>(s) : "";
}

std::string glRendererName() { return glString(GL_RENDERER); }
std::string glVersionString() { return glString(GL_VERSION); }

void readFramebufferRGBA(unsigned fbo, int width, int height, std::vector<uint8_t>& rgba) {
  const size_t row = size_t(width) * 4;
  rgba.resize(row * size_t(height));
  if (rgba.empty()) return;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  std::vector<uint8_t> tmp(row);
  for (int y = 0; y < height / 2; ++y) {
    uint8_t* a = rgba.data() + size_t(y) * row;
    uint8_t* b = rgba.data() + size_t(height - 1 - y) * row;
    std::memcpy(tmp.data(), a, row);
    std::memcpy(a, b, row);
    std::memcpy(b, tmp.data(), row);
  }
}

std::unique_ptr<HeadlessContext> HeadlessContext::create(int width, int height, std::string* err) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384) {
    if (err)
      *err = "HeadlessContext: size " + std::to_string(width) + "x" + std::to_string(height) + " out of range 1..16384";
    return nullptr;
  }
  // Depth/stencil of the default framebuffer are unused (we draw into our own FBOs).
  const int attribs[] = {OSMESA_FORMAT,
                         OSMESA_RGBA,
                         OSMESA_DEPTH_BITS,
                         0,
                         OSMESA_STENCIL_BITS,
                         0,
                         OSMESA_ACCUM_BITS,
                         0,
                         OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION,
                         3,
                         OSMESA_CONTEXT_MINOR_VERSION,
                         3,
                         0};
  OSMesaContext ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!ctx) {
    if (err) *err = "HeadlessContext: OSMesaCreateContextAttribs failed (no GL 3.3 core profile in this Mesa?)";
    return nullptr;
  }
  std::unique_ptr<HeadlessContext> c(new HeadlessContext());
  c->ctx_ = ctx;
  c->width_ = width;
  c->height_ = height;
  c->buffer_.reset(new unsigned char[size_t(width) * size_t(height) * 4]());
  if (!c->makeCurrent()) {
    if (err) *err = "HeadlessContext: OSMesaMakeCurrent failed";
    return nullptr;
  }
  if (!loadGL(reinterpret_cast<GLProcLoader>(OSMesaGetProcAddress), err)) return nullptr;
  return c;
}

HeadlessContext::~HeadlessContext() {
  if (ctx_) OSMesaDestroyContext(static_cast<OSMesaContext>(ctx_));
}

bool HeadlessContext::makeCurrent() {
  // Y_UP = 0: row 0 of buffer_ is the top row (only matters for readers of buffer_).
  if (!OSMesaMakeCurrent(static_cast<OSMesaContext>(ctx_), buffer_.get(), GL_UNSIGNED_BYTE, width_, height_))
    return false;
  OSMesaPixelStore(OSMESA_Y_UP, 0);
  return true;
}

std::string HeadlessContext::rendererName() const { return glRendererName(); }
std::string HeadlessContext::version() const { return glVersionString(); }

}  // namespace ponyhop

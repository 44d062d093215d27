#include "app/ui_gl.h"

#include <glad/gl.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <stdexcept>

#include "engine/gl_context.h"
#include "physics/stage_times.h"

namespace ponyhop {

UiGl::UiGl() {
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) throw std::runtime_error("ImGui OpenGL 3 backend: init failed");
}

UiGl::~UiGl() { ImGui_ImplOpenGL3_Shutdown(); }

void UiGl::newFrame() { ImGui_ImplOpenGL3_NewFrame(); }

void UiGl::compose(const Renderer& renderer, unsigned fbo, int width, int height, int scene_width, Times* times) {
  const auto t0 = Clock::now();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, width, height);
  glDisable(GL_SCISSOR_TEST);
  // The panel's background (it draws none of its own: Panel::build), and any gap ImGui leaves.
  const ImVec4 bg = ImGui::GetStyle().Colors[ImGuiCol_WindowBg];
  glClearColor(bg.x, bg.y, bg.z, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  // The scene's one copy on its way to the screen (a draw on llvmpipe, whose window back buffer
  // takes no memory copy: docs/bench/render.md, session 24), scaled up for a draft view.
  if (scene_width > 0 && renderer.width() > 0) renderer.blitTo(fbo, scene_width, height);
  if (times) {
    glFinish();
    times->copy_ms = msSince(t0);
  }
  const auto t1 = Clock::now();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, width, height);
  if (ImDrawData* d = ImGui::GetDrawData()) ImGui_ImplOpenGL3_RenderDrawData(d);
  if (times) {
    glFinish();
    times->panel_ms = msSince(t1);
  }
}

OffscreenTarget::OffscreenTarget(int width, int height) : width_(width), height_(height) {
  glGenFramebuffers(1, &fbo_);
  glGenRenderbuffers(1, &color_);
  glBindRenderbuffer(GL_RENDERBUFFER, color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) throw std::runtime_error("panel frame: framebuffer incomplete");
}

OffscreenTarget::~OffscreenTarget() {
  glDeleteFramebuffers(1, &fbo_);
  glDeleteRenderbuffers(1, &color_);
}

void OffscreenTarget::readPixels(std::vector<uint8_t>& rgba) const { readFramebufferRGBA(fbo_, width_, height_, rgba); }

}  // namespace ponyhop

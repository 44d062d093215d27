#include "app/ui_gl.h"

#include <glad/gl.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "engine/gl_context.h"
#include "physics/stage_times.h"

namespace ponyhop {

UiGl::UiGl() {
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) throw std::runtime_error("ImGui OpenGL 3 backend: init failed");
}

UiGl::~UiGl() {
  if (panel_fbo_) glDeleteFramebuffers(1, &panel_fbo_);
  if (panel_tex_) glDeleteTextures(1, &panel_tex_);
  ImGui_ImplOpenGL3_Shutdown();
}

void UiGl::setPanelCache(bool on) {
  cache_on_ = on;
  panel_valid_ = false;
  known_ = false;
}

void UiGl::setTargetKeeps(bool on) {
  keeps_ = on;
  panel_valid_ = false;
  known_ = false;
}

void UiGl::newFrame() { ImGui_ImplOpenGL3_NewFrame(); }

namespace {

template <typename T>
void append(std::vector<uint8_t>& out, const T* p, size_t n) {
  const auto* b = reinterpret_cast<const uint8_t*>(p);
  out.insert(out.end(), b, b + n * sizeof(T));
}
template <typename T>
void appendValue(std::vector<uint8_t>& out, const T& v) {
  append(out, &v, 1);
}

// A draw data holding some of the frame's lists, over the rectangle [x0, x0 + w) x the frame's
// height (ImGui's coordinates): the backend projects that rectangle onto the bound framebuffer.
struct PartialDrawData {
  std::vector<ImDrawList*> lists;
  ImDrawData data;
  void make(const ImDrawData& whole, float x0, float w) {
    data.Clear();
    data.Valid = true;
    data.CmdListsCount = int(lists.size());
    data.CmdLists = lists.data();
    for (const ImDrawList* l : lists) {
      data.TotalVtxCount += l->VtxBuffer.Size;
      data.TotalIdxCount += l->IdxBuffer.Size;
    }
    data.DisplayPos = ImVec2(x0, whole.DisplayPos.y);
    data.DisplaySize = ImVec2(w, whole.DisplaySize.y);
    data.FramebufferScale = whole.FramebufferScale;
  }
};

}  // namespace

bool UiGl::composeSaving(const Renderer& renderer, unsigned fbo, int width, int height, int scene_width, bool scene_new,
                         Times* times) {
  ImDrawData* d = ImGui::GetDrawData();
  if (!d || !d->Valid || scene_width <= 0 || scene_width >= width || renderer.width() <= 0) return false;
  const float sx = d->FramebufferScale.x > 0.0f ? d->FramebufferScale.x : 1.0f;
  const float panel_x0 = d->DisplayPos.x + float(scene_width) / sx;  // the panel's left edge, ImGui's coordinates
  const ImDrawList* background = ImGui::GetBackgroundDrawList();
  PartialDrawData overlay, panel;
  for (int i = 0; i < d->CmdListsCount; ++i) {
    ImDrawList* l = d->CmdLists[i];
    for (const ImDrawCmd& c : l->CmdBuffer)
      if (c.UserCallback) return false;
    if (l == background) {
      // The overlay is drawn over the scene apart from the panel: it must stay off the panel.
      for (const ImDrawVert& v : l->VtxBuffer)
        if (v.pos.x > panel_x0) return false;
      overlay.lists.push_back(l);
    } else {
      // Drawn into the panel's columns (or texture) alone: nothing may reach left of them.
      for (const ImDrawCmd& c : l->CmdBuffer) {
        // What a command can touch: its vertices' extent within its clip rectangle (a window's
        // frame is drawn under the whole display's clip rectangle, inside the window).
        float x_min = 1e30f;
        for (unsigned k = 0; k < c.ElemCount; ++k)
          x_min = std::min(x_min, l->VtxBuffer[int(c.VtxOffset + l->IdxBuffer[int(c.IdxOffset + k)])].pos.x);
        if (c.ElemCount > 0 && std::max(x_min, c.ClipRect.x) < panel_x0) return false;
      }
      panel.lists.push_back(l);
    }
  }
  const ImVec4 bg = ImGui::GetStyle().Colors[ImGuiCol_WindowBg];

  // What the panel's columns, and the view's overlay, are drawn from, whole.
  const auto signature = [&](std::vector<uint8_t>& sig, const std::vector<ImDrawList*>& lists) {
    sig.clear();
    appendValue(sig, width);
    appendValue(sig, scene_width);
    appendValue(sig, height);
    appendValue(sig, panel_x0);
    appendValue(sig, d->DisplayPos);
    appendValue(sig, d->DisplaySize);
    appendValue(sig, d->FramebufferScale);
    appendValue(sig, bg);
    for (const ImDrawList* l : lists) {
      appendValue(sig, l->VtxBuffer.Size);
      appendValue(sig, l->IdxBuffer.Size);
      appendValue(sig, l->CmdBuffer.Size);
      append(sig, l->VtxBuffer.Data, size_t(l->VtxBuffer.Size));
      append(sig, l->IdxBuffer.Data, size_t(l->IdxBuffer.Size));
      for (const ImDrawCmd& c : l->CmdBuffer) {  // field by field: the struct's padding is not data
        appendValue(sig, c.ClipRect);
        appendValue(sig, c.TextureId);
        appendValue(sig, c.VtxOffset);
        appendValue(sig, c.IdxOffset);
        appendValue(sig, c.ElemCount);
      }
    }
  };
  signature(sig_, panel.lists);
  signature(overlay_now_, overlay.lists);

  // What changed since the last compose into this target.
  const bool same_target =
      known_ && known_fbo_ == fbo && known_w_ == width && known_h_ == height && known_scene_w_ == scene_width;
  const bool panel_changed = !panel_valid_ || sig_ != panel_sig_;
  Damage damage;
  damage.view = !same_target || scene_new || overlay_now_ != overlay_sig_;
  damage.panel = !same_target || panel_changed;
  if (!keeps_ && damage.any()) damage.view = damage.panel = true;  // the target is not kept: a frame is drawn whole

  const auto t0 = Clock::now();
  glDisable(GL_SCISSOR_TEST);
  // The scene's one copy: it covers the view's columns, so no clear under it.
  if (damage.view) renderer.blitTo(fbo, scene_width, height);
  if (times) {
    glFinish();
    times->copy_ms = msSince(t0);
  }
  const auto t1 = Clock::now();
  bool drawn = false;
  // ImGui's panel into the bound framebuffer; the signature it was drawn from is kept.
  auto drawPanel = [&] {
    panel.make(*d, d->DisplayPos.x, d->DisplaySize.x);
    ImGui_ImplOpenGL3_RenderDrawData(&panel.data);
    panel_sig_.swap(sig_);
    panel_valid_ = true;
    drawn = true;
    if (times) {
      glFinish();
      times->panel_redraw_ms = msSince(t1);
    }
  };
  if (damage.panel && keeps_) {
    // The panel straight into the target's columns, over its background: ImGui draws it with the
    // frame's own projection, as in a frame drawn whole.
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, width, height);
    glEnable(GL_SCISSOR_TEST);
    glScissor(scene_width, 0, width - scene_width, height);
    glClearColor(bg.x, bg.y, bg.z, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glDisable(GL_SCISSOR_TEST);
    drawPanel();
    glDisable(GL_SCISSOR_TEST);
  } else if (damage.panel) {
    if (panel_changed) {
      // The texture is the whole frame's size and ImGui draws into it with the frame's own
      // projection, so the panel's pixels are rasterized exactly as in the frame (a texture of the
      // panel's columns alone, drawn with its origin moved, came out up to 1 in 255 off on a few
      // hundred edge pixels). It is cleared whole (llvmpipe's fastest fill, and only when the panel
      // changed) and only the panel's columns are copied.
      if (panel_w_ != width || panel_h_ != height || !panel_tex_) {
        if (!panel_tex_) glGenTextures(1, &panel_tex_);
        if (!panel_fbo_) glGenFramebuffers(1, &panel_fbo_);
        glBindTexture(GL_TEXTURE_2D, panel_tex_);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glBindTexture(GL_TEXTURE_2D, 0);
        glBindFramebuffer(GL_FRAMEBUFFER, panel_fbo_);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, panel_tex_, 0);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
          glBindFramebuffer(GL_FRAMEBUFFER, fbo);
          panel_valid_ = false;
          return false;  // (nothing drawn into fbo but the scene, which the direct path draws again)
        }
        panel_w_ = width;
        panel_h_ = height;
      }
      glBindFramebuffer(GL_FRAMEBUFFER, panel_fbo_);
      glViewport(0, 0, width, height);
      glClearColor(bg.x, bg.y, bg.z, 1.0f);  // the panel's background, as the direct path's clear
      glClear(GL_COLOR_BUFFER_BIT);
      drawPanel();
    }
    glDisable(GL_SCISSOR_TEST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, panel_fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo);
    glBlitFramebuffer(scene_width, 0, width, height, scene_width, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, width, height);
  if (damage.view && !overlay.lists.empty()) {
    overlay.make(*d, d->DisplayPos.x, d->DisplaySize.x);
    ImGui_ImplOpenGL3_RenderDrawData(&overlay.data);
  }
  if (times) {
    glFinish();
    times->panel_ms = msSince(t1);
    times->panel_drawn = drawn;
  }
  overlay_sig_.swap(overlay_now_);
  known_ = true;
  known_fbo_ = fbo;
  known_w_ = width;
  known_h_ = height;
  known_scene_w_ = scene_width;
  last_panel_drawn_ = drawn;
  last_damage_ = damage;
  return true;
}

UiGl::Damage UiGl::compose(const Renderer& renderer, unsigned fbo, int width, int height, int scene_width, Times* times,
                           bool scene_new) {
  if (cache_on_) {
    if (composeSaving(renderer, fbo, width, height, scene_width, scene_new, times)) return last_damage_;
    panel_valid_ = false;
    known_ = false;  // drawn whole below, without the records: the next frame is drawn whole too
  }
  if (times) times->panel_drawn = true;
  last_panel_drawn_ = true;
  last_damage_ = Damage{};
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
  return last_damage_;
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

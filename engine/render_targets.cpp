// The renderer's framebuffers and their textures: the main target (multisampled, or single-sample
// with the deferred surface targets and the half-resolution ground beside it), the output target
// of the anti-aliasing, the shadow map and the ground's shadow texture. Each is allocated when its
// size (or sample count) changes, not per frame.

#include "engine/renderer_impl.h"

namespace ponyhop {

// The bound 2D texture: bilinear, clamped at its edges.
static void linearClampToEdge() {
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

// `fbo` with an RGBA8 colour texture `tex` of w x h (bilinear, clamped), both made at the first
// call.
static void colorTarget(GLuint& fbo, GLuint& tex, int w, int h) {
  if (!fbo) {
    glGenFramebuffers(1, &fbo);
    glGenTextures(1, &tex);
  }
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  linearClampToEdge();
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
}

void Renderer::Impl::ensureTargets(int w, int h, int samples, bool post) {
  if (w == target_w && h == target_h && samples == target_samples && post == target_post) return;
  if (!msaa_fbo) {
    glGenFramebuffers(1, &msaa_fbo);
    glGenRenderbuffers(1, &msaa_color);
    glGenRenderbuffers(1, &msaa_depth);
    glGenTextures(1, &main_color_tex);
    glGenFramebuffers(1, &resolve_fbo);
    glGenRenderbuffers(1, &resolve_color);
    glGenRenderbuffers(1, &resolve_depth);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
  if (samples > 1) {
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_color);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_color);
  } else {
    glBindTexture(GL_TEXTURE_2D, main_color_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    linearClampToEdge();
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, main_color_tex, 0);
  }
  glBindRenderbuffer(GL_RENDERBUFFER, msaa_depth);
  if (samples > 1)
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, w, h);
  else
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth);
  glBindRenderbuffer(GL_RENDERBUFFER, resolve_color);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
  glBindRenderbuffer(GL_RENDERBUFFER, resolve_depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_color);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, resolve_depth);
  output_fbo = (samples > 1 || post) ? resolve_fbo : msaa_fbo;
  if (post) colorTarget(post_src_fbo, post_src_tex, w, h);
  if (samples == 1) ensureSingleSampleTargets(w, h);
  target_w = w;
  target_h = h;
  target_samples = samples;
  target_post = post;
}

// Beside a single-sample main target: the deferred shading's surface targets, sharing its depth
// buffer, and the half-resolution ground with the target that upsamples it into the main colour.
void Renderer::Impl::ensureSingleSampleTargets(int w, int h) {
  if (!surf_fbo) {
    glGenFramebuffers(1, &surf_fbo);
    glGenTextures(1, &surf_tex);
    glGenTextures(1, &key_tex);
    glGenTextures(1, &rest_tex);
  }
  // The surface in full float: the shadow search sees exactly the position the forward shader
  // has. The two parts of the radiance in half float (11 bits of mantissa: a relative step of
  // 1/2048, under a tenth of an 8-bit level after the tone curve and sRGB): half the bytes the
  // objects write and the deferred shading reads for them.
  for (GLuint t : {surf_tex, key_tex, rest_tex}) {
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, t == surf_tex ? GL_RGBA32F : GL_RGBA16F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, surf_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, surf_tex, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, key_tex, 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, rest_tex, 0);
  // The main colour target too: the pixels the objects pass finishes (objectsPass sets the draw
  // buffers).
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT3, GL_TEXTURE_2D, main_color_tex, 0);
  const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  glDrawBuffers(3, bufs);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth);
  if (!ground_lo_fbo) {
    glGenFramebuffers(1, &ground_up_fbo);
    glGenFramebuffers(1, &ground_lo_fbo);
    glGenTextures(1, &ground_lo_tex);
    glGenRenderbuffers(1, &ground_lo_depth);
  }
  ground_lo_w = (w + 1) / 2;
  ground_lo_h = (h + 1) / 2;
  glBindTexture(GL_TEXTURE_2D, ground_lo_tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, ground_lo_w, ground_lo_h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  linearClampToEdge();
  glBindFramebuffer(GL_FRAMEBUFFER, ground_lo_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, ground_lo_tex, 0);
  glBindRenderbuffer(GL_RENDERBUFFER, ground_lo_depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, ground_lo_w, ground_lo_h);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, ground_lo_depth);
  glBindFramebuffer(GL_FRAMEBUFFER, ground_up_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, main_color_tex, 0);
  // The upsampled ground kept between frames: the main target's format, so that its copy into it
  // is a memory copy.
  colorTarget(ground_full_fbo, ground_full_tex, w, h);
  ground_key.clear();  // new textures: nothing kept
  ground_full_key.clear();
}

void Renderer::Impl::ensureShadowMap(int size) {
  if (size == shadow_size) return;
  if (!shadow_fbo) {
    glGenFramebuffers(1, &shadow_fbo);
    glGenTextures(1, &shadow_tex);
  }
  glBindTexture(GL_TEXTURE_2D, shadow_tex);
  // 16 bits: the light is orthographic and its depth range is fitted to the casters, so a step is
  // the range / 65,536 (0.15 mm in a scene 10 m deep), far below the 1.5-texel normal offset that
  // keeps acne away. Half the bytes of a 24-bit map to clear, write and read: on llvmpipe the shadow
  // pass and every lookup are cheaper (measured: docs/RENDERING.md, Passes).
  glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT16, size, size, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_SHORT, nullptr);
  // Linear + compare mode: each lookup is a bilinearly weighted 2x2 depth test (hardware PCF).
  linearClampToEdge();
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex, 0);
  glDrawBuffer(GL_NONE);
  glReadBuffer(GL_NONE);
  shadow_size = size;
}

void Renderer::Impl::ensureGroundShadow(int size) {
  if (size == ground_shadow_size) return;
  if (!ground_shadow_fbo) {
    glGenFramebuffers(1, &ground_shadow_fbo);
    glGenTextures(1, &ground_shadow_tex);
    glGenRenderbuffers(1, &ground_shadow_depth);
  }
  glBindRenderbuffer(GL_RENDERBUFFER, ground_shadow_depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, size, size);
  glBindTexture(GL_TEXTURE_2D, ground_shadow_tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R8, size, size, 0, GL_RED, GL_UNSIGNED_BYTE, nullptr);
  linearClampToEdge();
  glBindFramebuffer(GL_FRAMEBUFFER, ground_shadow_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, ground_shadow_tex, 0);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, ground_shadow_depth);
  ground_shadow_size = size;
}

void Renderer::Impl::bindShadowTextures(bool ground_shadow) {
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, shadow_tex);
  glActiveTexture(GL_TEXTURE1);  // same texture, through a sampler without comparison
  glBindTexture(GL_TEXTURE_2D, shadow_tex);
  glBindSampler(1, raw_depth_sampler);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, ground_shadow ? ground_shadow_tex : 0);
  glActiveTexture(GL_TEXTURE0);
}

}  // namespace ponyhop

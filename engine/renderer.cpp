// The public Renderer (engine/renderer.h): its GL objects made once, the frame's draw list, and
// endFrame, which plans the frame (FramePlan) and runs its passes in order. The passes themselves
// are in render_passes.cpp; the other parts of the renderer: engine/renderer_impl.h.
//
// Index of this file:
// [SECTION] Pass timing
// [SECTION] Construction: programs, static geometry
// [SECTION] The draw list
// [SECTION] endFrame: the passes in order
// [SECTION] Read-back

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>

#include "engine/gl_context.h"
#include "engine/primitives.h"
#include "engine/renderer_impl.h"
#include "engine/shaders.h"
#include "physics/stage_times.h"

namespace ponyhop {

// ---------------------------------------------------------------------------------------------
// [SECTION] Pass timing

namespace {}  // namespace

void Renderer::Impl::beginPass(Pass p) {
  if (software_gl)
    pass_t0 = Clock::now();
  else
    glBeginQuery(GL_TIME_ELAPSED, queries[query_frame][p]);
}

void Renderer::Impl::endPass(Pass p, RenderStats& st) {
  if (!software_gl) {
    glEndQuery(GL_TIME_ELAPSED);
    queries_pending[query_frame] |= 1 << p;
    return;
  }
  glFinish();  // llvmpipe rasterizes the pass's bins here: its whole cost lands in this pass
  const double ms = msSince(pass_t0);
  (p == kShadowPass ? st.shadow_ms : p == kMainPass ? st.main_ms : st.resolve_ms) += ms;
}

// The previous frame's queries (same slot two frames ago is reused, so read before re-begin).
void Renderer::Impl::collectGpuTimes(RenderStats& st) {
  if (software_gl) return;
  const int prev = query_frame ^ 1;
  st.timed_on_gpu = true;
  double* out[kPasses] = {&st.shadow_ms, &st.main_ms, &st.resolve_ms};
  for (int p = 0; p < kPasses; ++p) {
    if (!(queries_pending[prev] & (1 << p))) continue;
    GLuint64 ns = 0;
    glGetQueryObjectui64v(queries[prev][p], GL_QUERY_RESULT, &ns);
    *out[p] = double(ns) * 1e-6;
  }
  queries_pending[prev] = 0;
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Construction: programs, static geometry

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}

Renderer::~Renderer() {
  if (!glDeleteProgram) return;  // GL never loaded: nothing was created
  Impl& I = *impl_;
  for (GLuint p : I.programs)
    if (p) glDeleteProgram(p);
  for (int i = 0; i < int(I.meshes.size()); ++i) release(MeshHandle{i});
  GLuint vaos[] = {I.hull_vao, I.hull_shadow_vao, I.empty_vao, I.lines_vao, I.hair_vao, I.grid_vao};
  glDeleteVertexArrays(6, vaos);
  GLuint bufs[] = {I.hull_vbo,  I.hull_ebo, I.hull_shadow_vbo, I.hull_shadow_ebo, I.hull_instances,
                   I.lines_vbo, I.hair_vbo, I.hair_ebo,        I.grid_ebo};
  glDeleteBuffers(9, bufs);
  GLuint fbos[] = {I.msaa_fbo,      I.resolve_fbo,   I.shadow_fbo,   I.ground_shadow_fbo, I.surf_fbo,
                   I.ground_lo_fbo, I.ground_up_fbo, I.post_src_fbo, I.ground_full_fbo};
  glDeleteFramebuffers(9, fbos);
  GLuint rbs[] = {I.msaa_color,          I.msaa_depth,    I.resolve_color,
                  I.ground_shadow_depth, I.resolve_depth, I.ground_lo_depth};
  glDeleteRenderbuffers(6, rbs);
  if (I.main_color_tex) glDeleteTextures(1, &I.main_color_tex);
  for (GLuint t : {I.surf_tex, I.key_tex, I.rest_tex, I.ground_lo_tex, I.post_src_tex, I.ground_full_tex})
    if (t) glDeleteTextures(1, &t);
  if (I.shadow_tex) glDeleteTextures(1, &I.shadow_tex);
  if (I.ground_shadow_tex) glDeleteTextures(1, &I.ground_shadow_tex);
  if (I.raw_depth_sampler) glDeleteSamplers(1, &I.raw_depth_sampler);
  if (I.queries[0][0]) glDeleteQueries(2 * Impl::kPasses, &I.queries[0][0]);
}

// Compiles and links every program; false + message at the first that fails.
bool Renderer::Impl::buildPrograms(std::string* err) {
  using namespace shaders;
  struct P {
    GLuint* out;
    const char* name;
    const char* vs;
    const char* fs;
    const char* defines = nullptr;
  };
  const P progs[] = {
      {&prog_mesh, "mesh", kMeshVS, kLitFS},
      {&prog_mesh_mat, "mesh with materials", kMeshMatVS, kMeshMatFS},
      {&prog_hull, "hull", kCapsuleVS, kLitFS},
      {&prog_ground, "ground", kGroundVS, kGroundFS},
      {&prog_ground_shadow, "ground shadow", kFullscreenVS, kGroundShadowFS},
      {&prog_lines, "lines", kLinesVS, kLinesFS},
      {&prog_mesh_depth, "mesh depth", kMeshVS, kDepthFS},
      {&prog_hull_depth, "hull depth", kCapsuleVS, kDepthFS},
      {&prog_post, "post AA", kPostVS, kPostAaFS},
      {&prog_bg, "background", kFullscreenVS, kBackgroundFS},
      {&prog_hair, "hair", kHairVS, kHairFS},
      {&prog_hair_depth, "hair depth", kHairVS, kDepthFS},
      {&prog_mesh_split, "mesh (deferred)", kMeshVS, kLitFS, kSplitLightDefine},
      {&prog_mesh_mat_split, "mesh with materials (deferred)", kMeshMatVS, kMeshMatFS, kSplitLightDefine},
      {&prog_mesh_hair, "mesh with a hair region", kMeshMatVS, kMeshMatFS, kScalpHairDefine},
      {&prog_mesh_hair_split, "mesh with a hair region (deferred)", kMeshMatVS, kMeshMatFS, kScalpHairSplitDefine},
      {&prog_hair_only, "mesh, all hair", kMeshMatVS, kMeshMatFS, kHairOnlyDefine},
      {&prog_hair_only_split, "mesh, all hair (deferred)", kMeshMatVS, kMeshMatFS, kHairOnlySplitDefine},
      {&prog_hull_split, "hull (deferred)", kCapsuleVS, kLitFS, kSplitLightDefine},
      {&prog_hair_split, "hair (deferred)", kHairVS, kHairFS, kSplitLightDefine},
      {&prog_deferred, "deferred shading", kFullscreenVS, kDeferredFS},
      {&prog_deferred_class, "deferred shading (lit and unlit)", kFullscreenVS, kDeferredFS, kShadowClassifyDefine},
      {&prog_ground_up, "ground (upsampled)", kGroundUpVS, kGroundUpFS},
      {&prog_grid, "ground (grid)", kGridVS, kGridFS},
      {&prog_grid_shadow, "ground (grid, shadowed)", kGridVS, kGridFS, kGridShadowedDefine},
      {&prog_ground_near, "ground (near)", kGroundVS, kGroundFS, kGroundNearDefine},
      {&prog_ground_near_lit, "ground (near, lit)", kGroundVS, kGroundFS, kGroundNearLitDefine},
      {&prog_ground_lit, "ground (lit)", kGroundVS, kGroundFS, kGroundLitDefine},
      {&prog_ground_shadow_class, "ground shadow (classify)", kFullscreenVS, kGroundShadowFS, kShadowClassifyDefine},
      {&prog_post_class, "post AA (edges)", kPostVS, kPostAaFS, kPostEdgesDefine}};
  for (const P& p : progs) {
    if (!(*p.out = buildProgram(p.name, p.vs, p.fs, err, p.defines))) return false;
    programs.push_back(*p.out);
  }
  if (!(prog_mesh_lit = buildProgram("mesh (deferred, lit colour)", kMeshVS, kLitFS, err, kSplitLitDefine)))
    return false;
  programs.push_back(prog_mesh_lit);
  if (!(prog_hull_lit = buildProgram("hull (deferred, lit colour)", kCapsuleVS, kLitFS, err, kSplitLitDefine)))
    return false;
  programs.push_back(prog_hull_lit);
  return true;
}

// The primitives' templates, the raw-depth sampler and the streamed vertex arrays (lines, hair).
void Renderer::Impl::makeStaticGeometry() {
  // Hull template: 24 slices x 8 rings per cap (768 triangles); instanced. Smooth at the sizes
  // links have on screen (tens of pixels); the normals are exact, only the outline is polygonal.
  // The shadow pass draws a coarser one, 16 slices x 4 rings (256 triangles): llvmpipe's cost
  // there is per triangle, and its outline stays within 2 % of the radius of the true one (about
  // a shadow texel for the hopper's body), inside it, so that no surface shadows itself.
  glGenBuffers(1, &hull_instances);
  const auto makeHullVao = [&](int slices, int rings, GLuint& vao, GLuint& vbo, GLuint& ebo) {
    const HullTemplate ht = makeHullTemplate(slices, rings);
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(ht.vertices.size() * sizeof(ht.vertices[0])), ht.vertices.data(),
                 GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 4 * sizeof(float), nullptr);
    glGenBuffers(1, &ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(ht.indices.size() * sizeof(uint32_t)), ht.indices.data(),
                 GL_STATIC_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, hull_instances);
    const GLsizei stride = sizeof(HullInstance);
    const struct {
      GLuint index;
      GLint size;
      size_t offset;
    } inst[] = {{1, 4, offsetof(HullInstance, p0r0)},
                {2, 4, offsetof(HullInstance, p1r1)},
                {3, 4, offsetof(HullInstance, color_spec)},
                {4, 2, offsetof(HullInstance, shin_rim)}};
    for (const auto& a : inst) {
      glEnableVertexAttribArray(a.index);
      glVertexAttribPointer(a.index, a.size, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<const void*>(a.offset));
      glVertexAttribDivisor(a.index, 1);
    }
    return ht.indices.size();
  };
  const size_t hull_indices = makeHullVao(24, 8, hull_vao, hull_vbo, hull_ebo);
  hull_index_count = GLsizei(hull_indices);
  hull_triangles = hull_indices / 3;
  hull_shadow_index_count = GLsizei(makeHullVao(16, 4, hull_shadow_vao, hull_shadow_vbo, hull_shadow_ebo));

  glGenSamplers(1, &raw_depth_sampler);
  glSamplerParameteri(raw_depth_sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glSamplerParameteri(raw_depth_sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glSamplerParameteri(raw_depth_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glSamplerParameteri(raw_depth_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glSamplerParameteri(raw_depth_sampler, GL_TEXTURE_COMPARE_MODE, GL_NONE);

  glGenVertexArrays(1, &empty_vao);  // core profile: a draw needs a VAO even without attributes

  glGenVertexArrays(1, &lines_vao);
  glBindVertexArray(lines_vao);
  glGenBuffers(1, &lines_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, lines_vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(LineVertex), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(LineVertex),
                        reinterpret_cast<const void*>(offsetof(LineVertex, color)));

  // Hair: positions, tangents, normals, colours and (half width, occlusion) per vertex, streamed.
  glGenVertexArrays(1, &hair_vao);
  glBindVertexArray(hair_vao);
  glGenBuffers(1, &hair_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, hair_vbo);
  glGenBuffers(1, &hair_ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, hair_ebo);
  const size_t hair_attr[] = {offsetof(HairVertex, pos), offsetof(HairVertex, tangent), offsetof(HairVertex, normal),
                              offsetof(HairVertex, color), offsetof(HairVertex, half_width)};
  for (GLuint a = 0; a < 5; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, a == 4 ? 2 : 3, GL_FLOAT, GL_FALSE, sizeof(HairVertex),
                          reinterpret_cast<const void*>(hair_attr[a]));
  }
  glBindVertexArray(0);
}

bool Renderer::init(std::string* err) {
  if (!glCreateProgram) {
    if (err) *err = "Renderer::init: GL is not loaded (call loadGL or create a HeadlessContext first)";
    return false;
  }
  Impl& I = *impl_;
  if (!I.buildPrograms(err)) return false;
  I.makeStaticGeometry();
  I.box_mesh = upload(makeBoxMesh(Eigen::Vector3f(1, 1, 1))).id;
  {
    const std::string name = glRendererName();
    I.software_gl = name.find("llvmpipe") != std::string::npos || name.find("softpipe") != std::string::npos ||
                    name.find("swrast") != std::string::npos;
    if (!I.software_gl) glGenQueries(2 * Impl::kPasses, &I.queries[0][0]);
  }
  glGetIntegerv(GL_MAX_SAMPLES, &I.max_samples);
  if (GLenum e = glGetError(); e != GL_NO_ERROR) {
    if (err) *err = "Renderer::init: GL error " + std::to_string(e);
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// [SECTION] The draw list

void Renderer::beginFrame(const Camera& camera, const LightParams& light, const RenderParams& params) {
  Impl& I = *impl_;
  I.camera = camera;
  I.light = light;
  I.params = params;
  I.have_shadow_bounds = false;
  I.draw_bounds.setEmpty();
  I.still_bounds.setEmpty();
  I.part_bounds.clear();
  I.mesh_draws.clear();
  I.hulls.clear();
  I.lines.clear();
  I.hair_vertices.clear();
  I.hair_indices.clear();
  I.hair_draws.clear();
  I.in_frame = true;
}

void Renderer::setShadowBounds(const Eigen::AlignedBox3d& b) {
  impl_->have_shadow_bounds = !b.isEmpty();
  impl_->shadow_bounds = b;
}

void Renderer::drawMesh(MeshHandle h, const Eigen::Affine3d& model, const Material& m, const ScalpHair& hair,
                        bool still) {
  Impl& I = *impl_;
  if (h.id < 0 || h.id >= int(I.meshes.size()) || I.meshes[size_t(h.id)].vao == 0) return;
  MeshDraw d;
  d.mesh = h.id;
  d.model = model.matrix().cast<float>();
  d.normal = model.linear().inverse().transpose().cast<float>();
  d.material = m;
  d.hair = hair;
  d.part = int(I.part_bounds.size());
  d.still = still;
  I.mesh_draws.push_back(d);
  I.part_bounds.push_back(transformedBounds(model, I.meshes[size_t(h.id)].bbox));
  I.draw_bounds.extend(I.part_bounds.back());
  if (still) I.still_bounds.extend(I.part_bounds.back());
}

void Renderer::drawBox(const Eigen::Affine3d& pose, const Eigen::Vector3d& half, const Material& m, bool still) {
  Eigen::Affine3d T = pose;
  T.linear() = pose.linear() * half.asDiagonal();
  drawMesh(MeshHandle{impl_->box_mesh}, T, m, ScalpHair{}, still);
}

void Renderer::drawTaperedCapsule(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double r0, double r1,
                                  const Material& m) {
  Impl& I = *impl_;
  const Eigen::Vector3f c = srgbToLinear(m.color);
  HullInstance h{{float(p0.x()), float(p0.y()), float(p0.z()), float(std::max(r0, 0.0))},
                 {float(p1.x()), float(p1.y()), float(p1.z()), float(std::max(r1, 0.0))},
                 {c.x(), c.y(), c.z(), m.specular},
                 {m.shininess, m.rim}};
  I.hulls.push_back(h);
  I.part_bounds.push_back(hullBounds(p0, r0, p1, r1));
  I.draw_bounds.extend(I.part_bounds.back());
}

void Renderer::drawSphere(const Eigen::Vector3d& center, double r, const Material& m) {
  drawTaperedCapsule(center, center, r, r, m);
}

void Renderer::drawCapsule(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double r, const Material& m) {
  drawTaperedCapsule(p0, p1, r, r, m);
}

void Renderer::drawHair(const HairMesh& hair) {
  Impl& I = *impl_;
  if (hair.indices.empty()) return;
  const uint32_t base = uint32_t(I.hair_vertices.size());
  HairDraw d;
  d.first = I.hair_indices.size();
  d.count = hair.indices.size();
  d.shading = hair.shading;
  Eigen::AlignedBox3d bounds;
  for (const HairVertex& v : hair.vertices) {
    I.hair_vertices.push_back(v);
    const float r = std::abs(v.half_width);
    bounds.extend(Eigen::Vector3d(v.pos[0] - r, v.pos[1] - r, v.pos[2] - r));
    bounds.extend(Eigen::Vector3d(v.pos[0] + r, v.pos[1] + r, v.pos[2] + r));
  }
  I.part_bounds.push_back(bounds);
  I.draw_bounds.extend(bounds);
  for (uint32_t i : hair.indices) I.hair_indices.push_back(base + i);
  const std::vector<uint32_t>& shadow = hair.shadow_indices.empty() ? hair.indices : hair.shadow_indices;
  d.shadow_first = I.hair_indices.size();
  d.shadow_count = shadow.size();
  for (uint32_t i : shadow) I.hair_indices.push_back(base + i);
  I.hair_draws.push_back(d);
}

void Renderer::drawLine(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3f& color) {
  impl_->lines.push_back({{float(a.x()), float(a.y()), float(a.z())}, {color.x(), color.y(), color.z()}});
  impl_->lines.push_back({{float(b.x()), float(b.y()), float(b.z())}, {color.x(), color.y(), color.z()}});
}

// ---------------------------------------------------------------------------------------------
// [SECTION] endFrame: the passes in order

void Renderer::endFrame() {
  Impl& I = *impl_;
  const auto t0 = Clock::now();
  // Everything decided once: size, samples, the shadow map, the matrices, which passes run.
  const FramePlan f = I.planFrame();
  I.ensureTargets(f.w, f.h, f.samples, f.post);
  I.draft = f.draft;
  width_ = f.w;
  height_ = f.h;
  stats_ = RenderStats{};
  stats_.samples = f.samples;
  stats_.post_aa = f.post;
  stats_.draft = f.draft;
  I.collectGpuTimes(stats_);
  I.uploadFrameData();

  // Shadows: the casters' depth seen from the key light, then the ground's shadow texture.
  I.ground_shadow_boxed = false;
  if (f.shadows_on) {
    I.beginPass(Impl::kShadowPass);
    I.shadowMapPass(f);
    stats_.shadow_size = I.shadow_size;
    stats_.shadow_kept = I.shadow_kept;
    if (I.params.ground) I.groundShadowPass(f);
    I.endPass(Impl::kShadowPass, stats_);
  }

  // The main pass, into the main target.
  I.beginPass(Impl::kMainPass);
  stats_.draw_calls = 0;
  // Single-sample: the ground and the background at half resolution, before the objects.
  if (f.half_ground && !f.grid_ground) I.halfGroundPass(f, stats_);
  glViewport(0, 0, f.w, f.h);
  // ... upsampled over the frame; the background's own pass above the horizon (sky_row). Or the
  // ground at full resolution as a grid lit at its corners (FramePlan::grid_ground).
  if (f.grid_ground)
    I.gridGroundPass(f, stats_);
  else if (f.half_ground)
    I.upsampleGroundPass(f, stats_);
  // The objects; deferred, their shadows and finished colour once per visible pixel after them.
  I.objectsPass(f, stats_);
  stats_.shadow_marked = I.shadow_marked;
  if (f.deferred) I.deferredLightPass(f, stats_);
  // Otherwise the ground after the objects, and the background where nothing was drawn.
  if (!f.half_ground) I.groundAndBackgroundPass(f, stats_);
  // Debug lines over everything.
  if (!I.lines.empty()) I.linesPass(f, stats_);
  I.endPass(Impl::kMainPass, stats_);

  // Anti-aliasing into the output target: MSAA resolve, or the post-process filter.
  if (f.msaa || f.post) {
    I.beginPass(Impl::kResolvePass);
    I.antiAliasPass(f);
    I.endPass(Impl::kResolvePass, stats_);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!I.software_gl) I.query_frame ^= 1;
  I.in_frame = false;
  stats_.submit_ms = msSince(t0);
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Read-back

namespace {

void unpremultiplyAlpha(std::vector<uint8_t>& rgba) {
  for (size_t i = 0; i + 3 < rgba.size(); i += 4) {
    const int a = rgba[i + 3];
    if (a == 0 || a == 255) continue;
    for (int c = 0; c < 3; ++c) rgba[i + size_t(c)] = uint8_t(std::min(255, (rgba[i + size_t(c)] * 255 + a / 2) / a));
  }
}

}  // namespace

void Renderer::readPixels(std::vector<uint8_t>& rgba) {
  const auto t0 = Clock::now();
  readFramebufferRGBA(impl_->output_fbo, width_, height_, rgba);
  // Transparent: edge pixels hold colour * coverage (the samples over a clear of 0); PNG wants
  // straight alpha.
  if (impl_->params.transparent) unpremultiplyAlpha(rgba);
  stats_.readback_ms = msSince(t0);
}

void Renderer::blitTo(unsigned fbo, int w, int h) const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, impl_->output_fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, w, h, GL_COLOR_BUFFER_BIT,
                    (w == width_ && h == height_) ? GL_NEAREST : GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
}

}  // namespace ponyhop

// The passes of Renderer::endFrame, one function each, in the order it runs them, and the drawing
// they share. What each pass does and why: docs/RENDERING.md, Passes.
//
// Index of this file:
// [SECTION] Uniforms and draws shared by the passes
// [SECTION] The frame's streamed data
// [SECTION] Shadow passes: the shadow map, the ground's shadow texture
// [SECTION] The ground and the background
// [SECTION] The objects and their deferred shadows
// [SECTION] Debug lines
// [SECTION] Anti-aliasing

#include <algorithm>
#include <cmath>
#include <span>
#include <utility>

#include "engine/renderer_impl.h"

namespace ponyhop {

// ---------------------------------------------------------------------------------------------
// [SECTION] Uniforms and draws shared by the passes

// The ground's shadow texture has shadow_size / this texels a side (groundShadowPass).
constexpr int kGroundShadowDivisor = 4;
// Angular radius of the key light (rad) for the penumbra of the soft shadows.
constexpr double kKeyLightAngularRadius = 1.5 * 3.14159265358979 / 180.0;
// Widest penumbra (and blocker search radius) of the soft shadows, m; at least 2 texels, at most
// 48 (setCommonUniforms).
constexpr double kMaxPenumbraMetres = 0.03;

static GLint loc(GLuint prog, const char* name) { return glGetUniformLocation(prog, name); }
static void setMat4(GLuint prog, const char* name, const Eigen::Matrix4f& m) {
  glUniformMatrix4fv(loc(prog, name), 1, GL_FALSE, m.data());  // Eigen is column-major, as GL
}
static void setVec3(GLuint prog, const char* name, const Eigen::Vector3f& v) {
  glUniform3f(loc(prog, name), v.x(), v.y(), v.z());
}

void Renderer::Impl::setCommonUniforms(GLuint prog, const Eigen::Matrix4f& view_proj, const Eigen::Matrix4f& light_vp,
                                       float normal_offset, bool shadows_on) {
  glUseProgram(prog);
  setMat4(prog, "u_viewProj", view_proj);
  setMat4(prog, "u_lightViewProj", light_vp);
  setVec3(prog, "u_eye", camera.eye.cast<float>());
  Eigen::Vector3d ld = light.direction;
  if (ld.norm() < 1e-9) ld = Eigen::Vector3d(-0.5, 0.6, -1.0);
  ld.normalize();
  setVec3(prog, "u_lightDir", ld.cast<float>());
  const Eigen::Vector3f key = srgbToLinear(light.color.cast<float>()) * float(light.intensity);
  setVec3(prog, "u_lightColor", key);
  // Fill: from behind the camera, a little above and to the side, so faces toward the viewer
  // that the key misses are not flat.
  Eigen::Vector3d view = (camera.target - camera.eye);
  if (view.norm() < 1e-9) view = Eigen::Vector3d(0, 1, 0);
  view.normalize();
  Eigen::Vector3d side = view.cross(Eigen::Vector3d::UnitZ());
  if (side.norm() < 1e-6) side = Eigen::Vector3d::UnitX();
  side.normalize();
  const Eigen::Vector3d fill_dir = (view + 0.35 * side - 0.35 * Eigen::Vector3d::UnitZ()).normalized();
  setVec3(prog, "u_fillDir", fill_dir.cast<float>());
  setVec3(prog, "u_fillColor", Eigen::Vector3f(0.85f, 0.9f, 1.0f) * float(light.fill));
  const Eigen::Vector3f sky = srgbToLinear(params.background.cast<float>());
  setVec3(prog, "u_skyAmbient", sky * float(light.ambient));
  setVec3(prog, "u_groundAmbient",
          srgbToLinear(params.ground_color.cast<float>()).cwiseProduct(Eigen::Vector3f(1.0f, 0.95f, 0.9f)) *
              float(light.ambient) * 0.45f);
  glUniform1f(loc(prog, "u_exposure"), 0.6f);
  glUniform1i(loc(prog, "u_shadowMap"), 0);
  glUniform1f(loc(prog, "u_shadowTexel"), 1.0f / float(std::max(shadow_size, 1)));
  glUniform1f(loc(prog, "u_shadowSoftness"), float(softness_texels));
  glUniform1f(loc(prog, "u_normalOffset"), normal_offset);
  glUniform1i(loc(prog, "u_shadowsOn"), shadows_on ? 1 : 0);
  glUniform1i(loc(prog, "u_shadowDraft"), draft ? 1 : 0);
  glUniform1i(loc(prog, "u_shadowDepth"), 1);
  glUniform1f(loc(prog, "u_lightDepthRange"), float(frustum.depth_range));
  glUniform1f(loc(prog, "u_texelWorld"), float(std::max(frustum.texel_world, 1e-9)));
  // The sun is 0.27 deg in radius; a softer 1.5 deg reads better at the scale of a head.
  glUniform1f(loc(prog, "u_penumbraSlope"), float(std::tan(kKeyLightAngularRadius)));
  glUniform1f(loc(prog, "u_maxPenumbraTexels"),
              float(std::clamp(kMaxPenumbraMetres / std::max(frustum.texel_world, 1e-9), 2.0, 48.0)));
  const Eigen::Vector3f top = params.background.cast<float>().cwiseMax(0.0f).cwiseMin(1.0f);
  // Brighter, slightly warm towards the horizon: reads as sky haze; the ground fades into it.
  const Eigen::Vector3f bottom = top + (Eigen::Vector3f(0.97f, 0.96f, 0.94f) - top) * 0.55f;
  setVec3(prog, "u_bgTop", top);
  setVec3(prog, "u_bgBottom", bottom);
  glUniform2f(loc(prog, "u_viewport"), float(target_w), float(target_h));
}

// Back faces of a closed mesh are culled: the mesh's own winding and a mirroring model matrix
// decide which side is the back. Open meshes are drawn from both sides (they may be seen, or
// cast, through their holes).
static void cullFor(const GpuMesh& g, const Eigen::Matrix4f& model) {
  if (g.closed == 0) {
    glDisable(GL_CULL_FACE);
    return;
  }
  const bool mirrored = model.topLeftCorner<3, 3>().determinant() < 0.0f;
  glEnable(GL_CULL_FACE);
  glCullFace((g.closed > 0) != mirrored ? GL_BACK : GL_FRONT);
}

// A shadow level's largest error, in texels of the frame's shadow map (GpuMesh::shadow_levels).
// The map's depth is drawn with a slope-scaled offset and read 1.5 texels out along the normal
// (FramePlan::normal_offset), so a caster within a texel of the surface shadows no lit pixel of
// its own; measured on the head scenes at 1280x720: 0-10 pixels over the comparator's threshold
// (docs/RENDERING.md, Shadows).
constexpr double kShadowLevelTexels = 1.0;

std::pair<size_t, GLsizei> shadowRange(const GpuMesh& g, const Eigen::Matrix4f& model, double texel_world) {
  std::pair<size_t, GLsizei> range{0, g.index_count};
  const double scale = model.topLeftCorner<3, 3>().colwise().norm().maxCoeff();
  if (!(scale > 0.0)) return range;
  const double allowed = kShadowLevelTexels * texel_world / scale;
  for (const GpuMesh::ShadowLevel& l : g.shadow_levels)
    if (l.error <= allowed) range = {l.first, GLsizei(l.count)};
  return range;
}

// Meshes with their file's materials (main pass): one draw per part, its texture on unit 2. Those
// with a hair region by their own programs, with their ScalpHair: `hair_only` draws the triangles
// that are all hair (GpuMesh::hair_only), else the parts.
void Renderer::Impl::drawMaterialMeshes(GLuint p, bool hair, bool hair_only) {
  bool used = false;
  for (const MeshDraw& d : mesh_draws) {
    const GpuMesh& g = meshes[size_t(d.mesh)];
    if (!g.materials || g.hair != hair || (hair_only && g.hair_only.count == 0)) continue;
    if (!used) {
      glUseProgram(p);
      glUniform1i(loc(p, "u_baseTex"), 2);
      used = true;
    }
    if (hair) {
      setVec3(p, "u_hairColor", srgbToLinear(d.hair.color));
      glUniform2f(loc(p, "u_hairShading"), d.hair.shading.highlight, d.hair.shading.shift);
      setVec3(p, "u_hairAxis", d.hair.axis.cast<float>());
    }
    glUniformMatrix4fv(loc(p, "u_model"), 1, GL_FALSE, d.model.data());
    glUniformMatrix3fv(loc(p, "u_normalMat"), 1, GL_FALSE, d.normal.data());
    const Eigen::Vector3f c = srgbToLinear(d.material.color);
    glUniform4f(loc(p, "u_colorSpec"), c.x(), c.y(), c.z(), d.material.specular);
    glUniform2f(loc(p, "u_shinRim"), d.material.shininess, d.material.rim);
    glBindVertexArray(g.vao);
    cullFor(g, d.model);
    // The hair-only range, or the parts, without a copy of either (this runs for every draw).
    const std::span<const MeshPart> parts = hair_only ? std::span<const MeshPart>(&g.hair_only, 1) : g.parts;
    for (const MeshPart& part : parts) {
      const bool tex = part.texture >= 0 && size_t(part.texture) < g.textures.size();
      glUniform1i(loc(p, "u_hasTex"), tex ? 1 : 0);
      glActiveTexture(GL_TEXTURE2);
      glBindTexture(GL_TEXTURE_2D, tex ? g.textures[size_t(part.texture)] : 0);
      glDrawElements(GL_TRIANGLES, GLsizei(part.count), GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(size_t(part.first) * sizeof(uint32_t)));
    }
    glActiveTexture(GL_TEXTURE0);
  }
  glDisable(GL_CULL_FACE);
  glCullFace(GL_BACK);
}

void Renderer::Impl::drawGeometry(GLuint mesh_prog, GLuint hull_prog, const Eigen::Matrix4f& view_proj, bool depth_only,
                                  int still, GLuint mesh_lit_prog) {
  if (!mesh_draws.empty()) {
    GLuint p = 0;
    GLint l_model = -1, l_normal = -1, l_cs = -1, l_sr = -1;
    for (const MeshDraw& d : mesh_draws) {
      const GpuMesh& g = meshes[size_t(d.mesh)];
      // Below, with their own program; the skin of a hair region's mesh (GpuMesh::skin_count) here.
      if (g.materials && !depth_only && g.skin_count == 0) continue;
      if (still >= 0 && d.still != (still == 1)) continue;
      const GLuint want = mesh_lit_prog && g.convex ? mesh_lit_prog : mesh_prog;
      if (want != p) {
        p = want;
        glUseProgram(p);
        if (depth_only) setMat4(p, "u_viewProj", view_proj);
        l_model = loc(p, "u_model"), l_normal = loc(p, "u_normalMat"), l_cs = loc(p, "u_colorSpec"),
        l_sr = loc(p, "u_shinRim");
      }
      glUniformMatrix4fv(l_model, 1, GL_FALSE, d.model.data());
      glUniformMatrix3fv(l_normal, 1, GL_FALSE, d.normal.data());
      const Eigen::Vector3f c = srgbToLinear(d.material.color);
      glUniform4f(l_cs, c.x(), c.y(), c.z(), d.material.specular);
      glUniform2f(l_sr, d.material.shininess, d.material.rim);
      glBindVertexArray(g.vao);
      cullFor(g, d.model);
      if (depth_only) {
        const auto [first, count] = shadowRange(g, d.model, frustum.texel_world);
        glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, reinterpret_cast<const void*>(first * sizeof(uint32_t)));
      } else {
        glDrawElements(GL_TRIANGLES, g.materials ? g.skin_count : g.index_count, GL_UNSIGNED_INT, nullptr);
      }
    }
    glDisable(GL_CULL_FACE);
    glCullFace(GL_BACK);
  }
  if (!depth_only) {
    const bool split = mesh_prog == prog_mesh_split;
    drawMaterialMeshes(split ? prog_mesh_mat_split : prog_mesh_mat, false, false);
    drawMaterialMeshes(split ? prog_mesh_hair_split : prog_mesh_hair, true, false);
    drawMaterialMeshes(split ? prog_hair_only_split : prog_hair_only, true, true);
  }
  if (!hulls.empty() && still != 1) {
    glUseProgram(hull_prog);
    if (depth_only) setMat4(hull_prog, "u_viewProj", view_proj);
    glBindVertexArray(depth_only ? hull_shadow_vao : hull_vao);
    // Hulls are closed and wound counter-clockwise: cull their back faces in both passes (half
    // the rasterization; the front faces alone give the nearest depth seen from the light).
    glEnable(GL_CULL_FACE);
    glDrawElementsInstanced(GL_TRIANGLES, depth_only ? hull_shadow_index_count : hull_index_count, GL_UNSIGNED_INT,
                            nullptr, GLsizei(hulls.size()));
    glDisable(GL_CULL_FACE);
  }
  glBindVertexArray(0);
}

// Hair ribbons face the camera in the main pass and the light in the shadow pass; a strand is
// drawn at least about one pixel (or one shadow texel) wide so that it neither breaks up nor
// flickers.
void Renderer::Impl::drawHairs(const Eigen::Matrix4f& view_proj, bool depth_only, const Eigen::Vector3d& light_dir,
                               GLuint prog) {
  if (hair_draws.empty()) return;
  const GLuint p = depth_only ? prog_hair_depth : prog ? prog : prog_hair;
  glUseProgram(p);
  setMat4(p, "u_viewProj", view_proj);
  if (depth_only) {
    glUniform1i(loc(p, "u_faceLight"), 1);
    setVec3(p, "u_faceDir", light_dir.cast<float>());
    glUniform2f(loc(p, "u_minHalfWidth"), float(0.5 * frustum.texel_world), 0.0f);
  } else {
    glUniform1i(loc(p, "u_faceLight"), 0);
    const double per_metre = std::tan(0.5 * camera.fov * 3.14159265358979 / 180.0) / double(std::max(target_h, 1));
    glUniform2f(loc(p, "u_minHalfWidth"), 0.0f, float(per_metre));
  }
  glBindVertexArray(hair_vao);
  const GLint l_shading = loc(p, "u_hairShading");
  for (const HairDraw& d : hair_draws) {
    glUniform2f(l_shading, d.shading.highlight, d.shading.shift);
    const size_t first = depth_only ? d.shadow_first : d.first, count = depth_only ? d.shadow_count : d.count;
    glDrawElements(GL_TRIANGLES, GLsizei(count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(first * sizeof(uint32_t)));
  }
  glBindVertexArray(0);
}

// A full-screen program in two passes over the bound target, whose depth buffer is scratch:
// `first` writes the pixels it can decide and depth 0 at the others (gl_FragDepth); `second`, the
// costly one, then runs under the far-plane triangle with depth test GREATER, on those pixels
// only. llvmpipe runs both sides of a shader's branches, but its early depth test does skip
// blocks before shading. `first` = 0: `second` alone, everywhere. Leaves the depth test on with
// LESS and depth writes on. `first_color` false: `first` writes only the depth (the pixels it
// decides already hold their colour).
static void drawFullscreenTwoPass(GLuint vao, GLuint first, GLuint second, bool first_color = true) {
  glBindVertexArray(vao);
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_ALWAYS);
  if (first) {
    glUseProgram(first);
    if (!first_color) glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthFunc(GL_GREATER);
  }
  glDepthMask(GL_FALSE);
  glUseProgram(second);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  glBindVertexArray(0);
}

// ---------------------------------------------------------------------------------------------
// [SECTION] The frame's streamed data

// Uploads this frame's instance data once; both passes use it.
void Renderer::Impl::uploadFrameData() {
  if (!hulls.empty()) {
    glBindBuffer(GL_ARRAY_BUFFER, hull_instances);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(hulls.size() * sizeof(HullInstance)), hulls.data(), GL_STREAM_DRAW);
  }
  if (!hair_draws.empty()) {
    glBindVertexArray(hair_vao);
    glBindBuffer(GL_ARRAY_BUFFER, hair_vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(hair_vertices.size() * sizeof(HairVertex)), hair_vertices.data(),
                 GL_STREAM_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(hair_indices.size() * sizeof(uint32_t)), hair_indices.data(),
                 GL_STREAM_DRAW);
    glBindVertexArray(0);
  }
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Shadow passes: the shadow map, the ground's shadow texture

// What the shadow map's and the ground shadow texture's kept texels depend on besides the moving
// casters (Impl::shadow_tex_key): the light's frustum, the map's and the ground texture's sizes,
// the filter's radius, draft, the ground's height and every still draw (its mesh and model
// matrix). Empty without still draws: nothing is kept.
std::vector<float> Renderer::Impl::shadowKey(const FramePlan& f, int ground_size) const {
  std::vector<float> k;
  for (const MeshDraw& d : mesh_draws) {
    if (!d.still) continue;
    k.push_back(float(d.mesh));
    k.insert(k.end(), d.model.data(), d.model.data() + 16);
  }
  if (k.empty()) return k;
  const Eigen::Matrix4f lvp = f.frustum.view_proj.cast<float>();
  k.insert(k.end(), lvp.data(), lvp.data() + 16);
  for (double v : {double(f.shadow_size), double(ground_size), f.softness_texels, double(f.draft),
                   f.frustum.texel_world, f.frustum.depth_range, params.ground_height})
    k.push_back(float(v));
  return k;
}

// Depth of the casters seen from the key light, into the map of the plan's size. With still draws
// whose key (shadowKey) is the last frame's, their depth is in the map already: only the texels
// the last frame's moving casters were drawn into are cleared and the still draws drawn again
// there (scissored), then the moving casters everywhere. The depth test keeps the nearest
// fragment whatever the order, so the map is the one drawn anew, bit for bit.
void Renderer::Impl::shadowMapPass(const FramePlan& f) {
  const int old_size = shadow_size;
  ensureShadowMap(f.shadow_size);
  if (shadow_size != old_size) shadow_tex_key.clear();  // a new texture
  softness_texels = f.softness_texels;
  frustum = f.frustum;
  glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
  glViewport(0, 0, shadow_size, shadow_size);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  std::vector<float> key = shadowKey(f, std::max(64, shadow_size / kGroundShadowDivisor));
  shadow_kept = !key.empty() && key == shadow_tex_key;
  glDisable(GL_CULL_FACE);  // open meshes cast from both sides (closed ones cull their back faces)
  // Slope-scaled bias in the depth pass (steep surfaces need more), plus the small normal offset
  // at lookup in the shader: together no acne, and the offset is too small to detach contact
  // shadows (no peter-panning).
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.5f, 2.0f);
  if (!shadow_kept) {
    glClear(GL_DEPTH_BUFFER_BIT);
    drawGeometry(prog_mesh_depth, prog_hull_depth, f.light_vp, true, key.empty() ? -1 : 1);
  } else if (!shadow_moving.empty()) {
    glEnable(GL_SCISSOR_TEST);
    for (const PixelRect& r : shadow_moving) {
      glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
      glClear(GL_DEPTH_BUFFER_BIT);
      drawGeometry(prog_mesh_depth, prog_hull_depth, f.light_vp, true, 1);
    }
    glDisable(GL_SCISSOR_TEST);
  }
  if (!key.empty()) drawGeometry(prog_mesh_depth, prog_hull_depth, f.light_vp, true, 0);
  drawHairs(f.light_vp, true, f.light_dir);
  glDisable(GL_POLYGON_OFFSET_FILL);
  // What the next frame clears: the moving casters' texels (two texels more: the rasterized
  // triangles lie inside their boxes), in as few rectangles as cost no more texels.
  shadow_tex_key = std::move(key);
  shadow_moving.clear();
  if (!shadow_tex_key.empty()) {
    casterTexelBoxes(f.frustum.view_proj, 2.0 * f.frustum.texel_world, shadow_size, shadow_moving, true);
    mergeRects(shadow_moving, 0);
  }
}

// The ground's shadow once per frame into a texture over the shadow map's square, instead of a
// blocker search + PCF per screen pixel of ground: the ground receives nothing else, and a soft
// shadow needs far fewer texels than the screen has ground pixels.
//
// Kept between frames with the shadow map's still part (shadowMapPass): a texel outside every
// moving caster's box, this frame's and the last one's, grown by the taps' reach, sees only the
// still casters' depth, the same as in the last frame, so it keeps its value; only the texels in
// those boxes are cleared and shaded again.
void Renderer::Impl::groundShadowPass(const FramePlan& f) {
  const LightFrustum& lf = frustum;
  const int gs = std::max(64, shadow_size / kGroundShadowDivisor);
  const int old_size = ground_shadow_size;
  ensureGroundShadow(gs);
  if (ground_shadow_size != old_size) ground_shadow_key.clear();  // a new texture
  glBindFramebuffer(GL_FRAMEBUFFER, ground_shadow_fbo);
  glViewport(0, 0, gs, gs);
  bindShadowTextures(false);  // the ground texture is the target here
  // Only the texels near a caster are shaded: a texel whose taps find no blocker is fully lit
  // (1), as the cleared texture is. Each caster's box (casterTexelBoxes) is grown by the widest
  // reach of the taps (the blocker search's kMaxPenumbraMetres, at least 2 texels; draft's 8
  // texels at most), a texel of bilinear footprint, the normal offset (2.25 texels) and two
  // ground texels: the texture is the same as with every texel shaded. One box per caster, not
  // the box around them all: on hopper_terrain the terrain's blocks and the hopper leave most of
  // the box around them empty.
  glClearColor(1.0f, 0.0f, 0.0f, 1.0f);
  glDepthMask(GL_TRUE);
  const double ground_texel = lf.texel_world * double(shadow_size) / double(gs);
  const double reach = kMaxPenumbraMetres + 12.0 * lf.texel_world + 2.0 * ground_texel;
  casterTexelBoxes(lf.view_proj, reach, gs, ground_shadow_boxes);
  ground_shadow_light = f.light_dir;
  ground_shadow_reach = reach + ground_texel;  // and a texel of the bilinear lookup's footprint
  ground_shadow_boxed = !ground_shadow_boxes.empty();
  // Kept: the texels to draw again are those in this frame's or the last frame's moving boxes.
  const bool kept = shadow_kept && ground_shadow_key == shadow_tex_key;
  std::vector<PixelRect> moving, redo, shade, outside;
  if (!shadow_tex_key.empty()) casterTexelBoxes(lf.view_proj, reach, gs, moving, true);
  PixelRect all{0, 0, gs, gs};
  if (kept) {
    redo = moving;
    redo.insert(redo.end(), ground_shadow_moving.begin(), ground_shadow_moving.end());
    partitionRects(redo, all, shade, outside);
    redo.swap(shade);
    glEnable(GL_SCISSOR_TEST);
    for (const PixelRect& r : redo) {
      glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    }
    glDisable(GL_SCISSOR_TEST);
  } else {
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  }
  ground_shadow_key = shadow_tex_key;
  ground_shadow_moving = std::move(moving);
  if (ground_shadow_boxed) {
    const Eigen::Matrix4f lvp = lf.view_proj.cast<float>();
    for (GLuint p : {prog_ground_shadow_class, prog_ground_shadow}) {
      setCommonUniforms(p, lvp, lvp, float(1.5 * lf.texel_world), true);
      setMat4(p, "u_invLightViewProj", lf.view_proj.inverse().cast<float>());
      glUniform1f(loc(p, "u_groundZ"), float(params.ground_height));
      glUniform2f(loc(p, "u_groundShadowSize"), float(gs), float(gs));
    }
    glEnable(GL_SCISSOR_TEST);
    // The blocker search writes the fully lit and umbra texels, the filter runs on the
    // others (draft has no search: one pass); over the boxes' union cut into disjoint pieces.
    partitionRects(ground_shadow_boxes, all, rects, outside);
    if (kept) {  // only where they meet the pieces drawn again (both disjoint)
      shade.clear();
      for (const PixelRect& a : rects)
        for (const PixelRect& b : redo)
          if (!(a & b).empty()) shade.push_back(a & b);
      rects.swap(shade);
    }
    for (const PixelRect& b : rects) {
      glScissor(b.x0, b.y0, b.x1 - b.x0, b.y1 - b.y0);
      drawFullscreenTwoPass(empty_vao, f.draft ? 0 : prog_ground_shadow_class, prog_ground_shadow);
    }
    glDisable(GL_SCISSOR_TEST);
  }
  glDepthMask(GL_TRUE);
}

// ---------------------------------------------------------------------------------------------
// [SECTION] The ground and the background

// The ground square into the bound target of vw x vh pixels, in parts, each with the least its
// pixels need (the colours are the same): the square inside the circle where the fade starts,
// without the fade (GROUND_NEAR), and without the shadow lookup outside the pixel rectangle of
// the shadow texture's shaded texels (GROUND_LIT); then the ring around it to the edge, with the
// fade, and again without the shadow lookup outside that rectangle (the ring is about 40 % of the
// ground's shading on the hopper scenes at 1280x720, and a shadow rarely reaches it). Most ground
// pixels are in the square, and the shadows in a small part of it. Leaves the empty VAO bound.
void Renderer::Impl::drawGroundParts(const FramePlan& f, int vw, int vh, const PixelRect& clip) {
  const Camera& cam = camera;
  for (GLuint p : {prog_ground, prog_ground_lit, prog_ground_near, prog_ground_near_lit}) {
    setFrameUniforms(p, f);
    glUniform3f(loc(p, "u_quadCenter"), float(cam.target.x()), float(cam.target.y()), float(params.ground_height));
    glUniform1f(loc(p, "u_quadHalf"), float(f.ground_half));
    glUniform1f(loc(p, "u_quadInner"), 0.0f);
    glUniform1i(loc(p, "u_transparent"), params.transparent ? 1 : 0);
    setVec3(p, "u_groundAlbedo", srgbToLinear(params.ground_color.cast<float>()));
    glUniform1f(loc(p, "u_gridSpacing"), float(std::max(params.grid_spacing, 0.0)));
    glUniform3f(loc(p, "u_fadeCenter"), float(cam.target.x()), float(cam.target.y()), 0.0f);
    glUniform2f(loc(p, "u_fade"), float(f.fade_start), float(f.fade_end));
    glUniform1i(loc(p, "u_groundShadow"), 2);
    glUniform2f(loc(p, "u_viewport"), float(vw), float(vh));
  }
  glBindVertexArray(empty_vao);
  const float inner = float(f.fade_start / std::sqrt(2.0) * 0.999);
  PixelRect sr{};
  bool whole = false;
  const bool boxed = f.shadows_on && groundShadowRect(f.view_proj, vw, vh, sr, whole);
  for (GLuint p : {prog_ground_near, prog_ground_near_lit}) {
    glUseProgram(p);
    glUniform1f(loc(p, "u_quadHalf"), inner);
  }
  // Each draw scissored to its part of the clip rectangle (none: not drawn).
  glEnable(GL_SCISSOR_TEST);
  const auto draw = [&](const PixelRect& part, GLint count) {
    const PixelRect r = part & clip;
    if (r.empty()) return;
    glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, count);
  };
  const PixelRect all{0, 0, vw, vh};
  const PixelRect around[4] = {
      {0, 0, vw, sr.y0}, {0, sr.y1, vw, vh}, {0, sr.y0, sr.x0, sr.y1}, {sr.x1, sr.y0, vw, sr.y1}};
  // Each part (the square, strip of 4; the ring, strip of 10) with the shadow lookup inside the
  // shadow's rectangle and without it around.
  const auto drawPart = [&](GLuint shadowed, GLuint lit, GLint count) {
    if (!boxed || whole) {
      glUseProgram(boxed ? shadowed : lit);
      draw(all, count);
    } else {
      glUseProgram(shadowed);
      draw(sr, count);
      glUseProgram(lit);
      for (const PixelRect& a : around) draw(a, count);
    }
  };
  drawPart(prog_ground_near, prog_ground_near_lit, 4);
  for (GLuint p : {prog_ground, prog_ground_lit}) {
    glUseProgram(p);
    glUniform1f(loc(p, "u_quadInner"), inner);
  }
  drawPart(prog_ground, prog_ground_lit, 10);
  glDisable(GL_SCISSOR_TEST);
}

// Everything the half-resolution ground and the upsampled one depend on outside the ground's
// shadow rectangle (groundShadowRect): the uniforms drawGroundParts, the background and the
// upsampling set, but for the light's matrix and the shadow texture, which only that rectangle
// reads (outside it the ground is lit: the shadow texture reads 1 there, GROUND_LIT assumes 1).
// Equal keys, equal pixels there.
std::vector<float> Renderer::Impl::groundKey(const FramePlan& f) const {
  std::vector<float> k(f.view_proj.data(), f.view_proj.data() + 16);
  const auto add = [&](const auto& v) {
    for (int i = 0; i < int(v.size()); ++i) k.push_back(float(v[i]));
  };
  add(camera.eye);
  add(camera.target);
  add(light.direction);
  add(light.color);
  add(params.background);
  add(params.ground_color);
  for (double v : {light.intensity, light.fill, light.ambient, params.grid_spacing, params.ground_height, f.fade_start,
                   f.fade_end, f.ground_half})
    k.push_back(float(v));
  for (int v : {int(params.transparent), ground_lo_w, ground_lo_h, f.w, f.h, f.sky_row}) k.push_back(float(v));
  return k;
}

// The ground, then the background around it, in a half-size texture with a depth buffer of its
// own (no object in it): the texels around the ground's edge hold the background it fades into
// (or alpha 0 when transparent), so the upsampled edge blends into what is drawn beside it.
// First, before the objects: llvmpipe finishes a framebuffer's drawing at every switch, and this
// order has one switch fewer. While groundKey() stays the same, only the last frame's shadow
// rectangle and this frame's are drawn again (ground_lo_dirty): the rest is what it was.
void Renderer::Impl::halfGroundPass(const FramePlan& f, RenderStats& st) {
  const PixelRect all{0, 0, ground_lo_w, ground_lo_h};
  std::vector<float> key = groundKey(f);
  PixelRect shadow{0, 0, 0, 0};
  bool whole = false;
  if (!(f.shadows_on && groundShadowRect(f.view_proj, ground_lo_w, ground_lo_h, shadow, whole))) shadow = {0, 0, 0, 0};
  ground_lo_kept = key == ground_key && !ground_lo_whole && !whole;
  ground_lo_dirty = ground_lo_kept ? (ground_lo_shadow | shadow) & all : all;
  ground_key = std::move(key);
  ground_lo_shadow = shadow;
  ground_lo_whole = whole;
  if (ground_lo_dirty.empty()) return;
  const PixelRect& d = ground_lo_dirty;
  bindShadowTextures(true);
  glBindFramebuffer(GL_FRAMEBUFFER, ground_lo_fbo);
  glViewport(0, 0, ground_lo_w, ground_lo_h);
  glClearColor(0, 0, 0, 0);
  glEnable(GL_DEPTH_TEST);  // (without a shadow pass before it, the state is what the last frame left)
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glEnable(GL_SCISSOR_TEST);
  glScissor(d.x0, d.y0, d.x1 - d.x0, d.y1 - d.y0);
  // The colour needs no clear unless transparent: the ground, then the background where the depth
  // is still the cleared 1, write every texel the upsampling reads (the rows below sky_row / 2 +
  // 2); transparent, the texels without ground stay the cleared alpha 0.
  glClear(params.transparent ? GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT : GL_DEPTH_BUFFER_BIT);
  drawGroundParts(f, ground_lo_w, ground_lo_h, d);
  // Only the rows the upsampling below sky_row reads (its pixel row y taps rows y / 2 and
  // y / 2 + 1 at most).
  const PixelRect bg = d & PixelRect{0, 0, ground_lo_w, std::min(ground_lo_h, f.sky_row / 2 + 2)};
  if (!params.transparent && !bg.empty()) {
    setFrameUniforms(prog_bg, f);
    glUniform2f(loc(prog_bg, "u_viewport"), float(ground_lo_w), float(ground_lo_h));
    glDepthFunc(GL_LEQUAL);  // the far plane, where the depth is still the cleared 1
    glDepthMask(GL_FALSE);
    glEnable(GL_SCISSOR_TEST);
    glScissor(bg.x0, bg.y0, bg.x1 - bg.x0, bg.y1 - bg.y0);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
  }
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
  ++st.draw_calls;
}

// Into the bound target, inside `clip`: the half-resolution ground, a bilinear tap of it per
// pixel, below sky_row; above it the background's own pass.
void Renderer::Impl::upsampleGround(const FramePlan& f, const PixelRect& clip, RenderStats& st) {
  const int w = f.w;
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_SCISSOR_TEST);
  glBindVertexArray(empty_vao);
  if (const PixelRect r = clip & PixelRect{0, 0, w, f.sky_row}; !r.empty()) {
    const GLuint u = prog_ground_up;
    glUseProgram(u);
    glActiveTexture(GL_TEXTURE7);
    glBindTexture(GL_TEXTURE_2D, ground_lo_tex);
    glActiveTexture(GL_TEXTURE0);
    glUniform1i(loc(u, "u_groundLo"), 7);
    glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glActiveTexture(GL_TEXTURE7);
    glBindTexture(GL_TEXTURE_2D, 0);  // a render target again next frame
    glActiveTexture(GL_TEXTURE0);
    ++st.draw_calls;
  }
  backgroundRows(f, clip, f.sky_row, st);
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
}

// The ground and the background at full size, under the objects. When halfGroundPass kept the
// half-resolution ground, the upsampled one is kept too (ground_full_tex): only what the redrawn
// texels reach is upsampled again, and the whole is copied into the main target
// (glBlitFramebuffer of the same size and format: a memory copy on llvmpipe, about a quarter of
// the bilinear tap's cost).
void Renderer::Impl::upsampleGroundPass(const FramePlan& f, RenderStats& st) {
  PixelRect dirty{0, 0, 0, 0};
  if (!ground_lo_dirty.empty()) {
    // Pixel x taps the texels at (x + 0.5) w_lo / w - 0.5 and the next: a redrawn texel column c
    // reaches the pixels within 2 of 2c (3 for an odd width); 4 for the interpolation's rounding.
    constexpr int kReach = 4;
    const PixelRect& d = ground_lo_dirty;
    dirty = PixelRect{0, 0, f.w, f.h} &
            PixelRect{2 * d.x0 - kReach, 2 * d.y0 - kReach, 2 * d.x1 + kReach, 2 * d.y1 + kReach};
  }
  keptGroundPass(f, ground_lo_kept, dirty, &Impl::upsampleGround, st);
}

// The full-size ground into the main target by `draw`: straight into it when the ground is not
// kept; else into ground_full_tex (all of it when its key is stale, else `dirty` alone) and copied
// into the main target from there.
void Renderer::Impl::keptGroundPass(const FramePlan& f, bool kept, const PixelRect& dirty, GroundDraw draw,
                                    RenderStats& st) {
  const PixelRect all{0, 0, f.w, f.h};
  if (!kept) {
    ground_full_key.clear();
    glBindFramebuffer(GL_FRAMEBUFFER, ground_up_fbo);
    (this->*draw)(f, all, st);
    return;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, ground_full_fbo);
  if (ground_full_key != ground_key) {
    (this->*draw)(f, all, st);
    ground_full_key = ground_key;
  } else if (!dirty.empty()) {
    (this->*draw)(f, dirty, st);
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, ground_full_fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, ground_up_fbo);
  glBlitFramebuffer(0, 0, f.w, f.h, 0, 0, f.w, f.h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  ++st.draw_calls;
}

// The background's own pass over the rows from `row` up, inside `clip` (the scissor test on, the
// empty vertex array bound).
void Renderer::Impl::backgroundRows(const FramePlan& f, const PixelRect& clip, int row, RenderStats& st) {
  const PixelRect r = clip & PixelRect{0, row, f.w, f.h};
  if (r.empty()) return;
  setFrameUniforms(prog_bg, f);
  glUniform2f(loc(prog_bg, "u_viewport"), float(f.w), float(f.h));
  glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  ++st.draw_calls;
}

// Into the bound target (main_color_tex's size), inside `clip`: the grid ground below grid_top,
// the background's own pass above it. The grid's cells are drawn by prog_grid but in the ground
// shadows' pixel rectangles (groundShadowRects, one per caster's box), where prog_grid_shadow
// (GRID_SHADOWED) looks the shadow up per pixel (everywhere when they cannot be bounded).
void Renderer::Impl::drawGridGround(const FramePlan& f, const PixelRect& clip, RenderStats& st) {
  const int w = f.w, h = f.h;
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_SCISSOR_TEST);
  glBindVertexArray(empty_vao);
  backgroundRows(f, clip, f.grid_top, st);
  const PixelRect below = clip & PixelRect{0, 0, w, f.grid_top};
  if (!below.empty()) {
    // 64-pixel cells: the lighting, the fade and the background are smooth at that scale (on the
    // hopper at 1280x720, 64- and 128-pixel cells' frames are within 0.013 of 32-pixel cells' in
    // `ponyhop diff`'s YIQ distance, about 2 of 255 steps), and llvmpipe's cost per triangle
    // counts: 32-pixel cells made the hopper's final frame about 1 ms dearer than 64-pixel ones.
    constexpr int kCell = 64;
    const int cols = (w + kCell - 1) / kCell, rows = (f.grid_top + kCell - 1) / kCell;
    const int all_rows = (h + kCell - 1) / kCell;
    if (!grid_vao) {
      glGenVertexArrays(1, &grid_vao);
      glGenBuffers(1, &grid_ebo);
    }
    glBindVertexArray(grid_vao);
    if (cols != grid_cols || all_rows != grid_rows) {
      grid_cols = cols;
      grid_rows = all_rows;
      std::vector<uint32_t> idx;
      idx.reserve(size_t(cols) * size_t(all_rows) * 6);
      const uint32_t stride = uint32_t(cols + 1);
      for (uint32_t j = 0; j < uint32_t(all_rows); ++j)
        for (uint32_t i = 0; i < uint32_t(cols); ++i) {
          const uint32_t a = j * stride + i;
          for (uint32_t v : {a, a + 1, a + stride, a + stride, a + 1, a + stride + 1}) idx.push_back(v);
        }
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, grid_ebo);
      glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(idx.size() * sizeof(uint32_t)), idx.data(), GL_STATIC_DRAW);
    }
    const Eigen::Matrix4f inv = f.view_proj.inverse();
    const Camera& cam = camera;
    for (GLuint p : {prog_grid, prog_grid_shadow}) {
      setFrameUniforms(p, f);
      setMat4(p, "u_invViewProj", inv);
      glUniform1f(loc(p, "u_gridCell"), float(kCell));
      glUniform1f(loc(p, "u_gridTop"), float(f.grid_top));
      glUniform1i(loc(p, "u_gridCols"), cols);
      glUniform1f(loc(p, "u_groundZ"), float(params.ground_height));
      glUniform1i(loc(p, "u_transparent"), 0);
      setVec3(p, "u_groundAlbedo", srgbToLinear(params.ground_color.cast<float>()));
      glUniform1f(loc(p, "u_gridSpacing"), float(std::max(params.grid_spacing, 0.0)));
      glUniform3f(loc(p, "u_fadeCenter"), float(cam.target.x()), float(cam.target.y()), 0.0f);
      glUniform2f(loc(p, "u_fade"), float(f.fade_start), float(f.fade_end));
      glUniform1i(loc(p, "u_groundShadow"), 2);
    }
    bool whole = false;
    const bool boxed = f.shadows_on && groundShadowRects(f.view_proj, w, h, rects, whole);
    // Each part scissored, drawing only the rows of cells it reaches (each corner is shaded
    // once a draw).
    const auto draw = [&](GLuint p, const PixelRect& part) {
      const PixelRect r = part & below;
      if (r.empty()) return;
      const int j0 = r.y0 / kCell, j1 = std::min((r.y1 + kCell - 1) / kCell, rows);
      if (j1 <= j0) return;
      glUseProgram(p);
      glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
      glDrawElements(GL_TRIANGLES, GLsizei(j1 - j0) * cols * 6, GL_UNSIGNED_INT,
                     reinterpret_cast<const void*>(size_t(j0) * size_t(cols) * 6 * sizeof(uint32_t)));
      ++st.draw_calls;
    };
    if (boxed) bindShadowTextures(true);
    if (boxed && whole) {
      draw(prog_grid_shadow, below);
    } else if (boxed) {
      // The shadows' rectangles (one per caster's box, groundShadowRects) and the rest, cut
      // into disjoint pieces.
      std::vector<PixelRect> inside, outside;
      partitionRects(rects, below, inside, outside);
      for (const PixelRect& r : inside) draw(prog_grid_shadow, r);
      for (const PixelRect& r : outside) draw(prog_grid, r);
    } else {
      draw(prog_grid, below);
    }
  }
  glDisable(GL_SCISSOR_TEST);
  glBindVertexArray(0);
}

// The ground and the background at full size, under the objects, as a grid lit at its corners
// (FramePlan::grid_ground), into the main target. While groundKey() stays the same (a fixed
// camera and light), it is kept in ground_full_tex as the upsampled ground is
// (upsampleGroundPass): drawn again only in the last frame's shadow rectangle and this frame's,
// and copied into the main target.
void Renderer::Impl::gridGroundPass(const FramePlan& f, RenderStats& st) {
  const PixelRect all{0, 0, f.w, f.h};
  std::vector<float> key = groundKey(f);
  key.push_back(-1.0f);  // the grid ground's: never a key of the half-resolution one
  PixelRect shadow{0, 0, 0, 0};
  bool whole = false;
  if (!(f.shadows_on && groundShadowRect(f.view_proj, f.w, f.h, shadow, whole))) shadow = {0, 0, 0, 0};
  const bool kept = key == ground_key && !ground_lo_whole && !whole;
  const PixelRect dirty = kept ? (ground_lo_shadow | shadow) & all : all;
  ground_key = std::move(key);
  ground_lo_shadow = shadow;
  ground_lo_whole = whole;
  ground_lo_kept = false;
  keptGroundPass(f, kept, dirty, &Impl::drawGridGround, st);
}

// Without the half-resolution ground: the ground after the objects (the early depth test skips
// the pixels they cover, and its nearer fragments still hide whatever is below it). It writes its
// depth, so that the background, last, fills only the pixels nothing was drawn on (none when
// transparent: alpha 0 there).
void Renderer::Impl::groundAndBackgroundPass(const FramePlan& f, RenderStats& st) {
  glBindVertexArray(empty_vao);
  if (params.ground) {
    drawGroundParts(f, f.w, f.h, PixelRect{0, 0, f.w, f.h});
    ++st.draw_calls;
  }
  if (!params.transparent) {
    glDepthFunc(GL_LEQUAL);  // the far plane, where the depth is still the cleared 1
    glDepthMask(GL_FALSE);
    setFrameUniforms(prog_bg, f);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
    ++st.draw_calls;
  }
  glBindVertexArray(0);
}

// ---------------------------------------------------------------------------------------------
// [SECTION] The objects and their deferred shadows

// Where the deferred shading must look. A convex caster never shadows its own lit faces (a face
// turned away from the light gets no key light at all), so a pixel of one can be shadowed only
// by another caster, and only where that caster's texels are within the shadow lookups' reach of
// the pixel's lookup point and nearer the light than it. Each caster's light-space box: its
// bounds' corners (a hull: its two spheres) in shadow-map coordinates, grown by the blocker
// search's and the filter's reach (u_maxPenumbraTexels, as setCommonUniforms sets it) and 3
// texels more (the filter's bilinear footprint, the rasterized outline, the hair's least width),
// from its nearest depth (less a texel's worth and two 16-bit steps) on. For a convex caster A
// and each other caster B whose box reaches A's, the box of B cut at A's farthest depth, brought
// back into the world (the light is orthographic: 8 corners) and projected, and A's own
// rectangle: the pixels of A that B can shadow lie in both. A caster that is not convex (a
// mesh, the hair) keeps its whole rectangle.
bool Renderer::Impl::deferredRects(const FramePlan& f, std::vector<PixelRect>& out) const {
  out.clear();
  struct Caster {
    Eigen::AlignedBox3d bounds;
    bool convex = false;
    double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30, z0 = 1e30, z1 = -1e30;  // light space, not grown
  };
  std::vector<Caster> casters;
  bool any_convex = !hulls.empty();
  for (const MeshDraw& d : mesh_draws) any_convex = any_convex || meshes[size_t(d.mesh)].convex;
  constexpr size_t kMaxCasters = 64;  // the pairs are tested on the CPU
  if (!any_convex || mesh_draws.size() + hulls.size() + 1 > kMaxCasters) return false;
  const Eigen::Matrix4d L = f.light_vp.cast<double>();
  // Shadow-map coordinates are 0.5 ndc + 0.5.
  const Eigen::Vector3d ax = 0.5 * L.block<1, 3>(0, 0).transpose(), ay = 0.5 * L.block<1, 3>(1, 0).transpose(),
                        az = 0.5 * L.block<1, 3>(2, 0).transpose();
  const auto add = [&](Caster& c, const Eigen::Vector3d& p, double r) {
    const double x = ax.dot(p) + 0.5 * L(0, 3) + 0.5, y = ay.dot(p) + 0.5 * L(1, 3) + 0.5,
                 z = az.dot(p) + 0.5 * L(2, 3) + 0.5;
    const double rx = r * ax.norm(), ry = r * ay.norm(), rz = r * az.norm();
    c.x0 = std::min(c.x0, x - rx), c.x1 = std::max(c.x1, x + rx);
    c.y0 = std::min(c.y0, y - ry), c.y1 = std::max(c.y1, y + ry);
    c.z0 = std::min(c.z0, z - rz), c.z1 = std::max(c.z1, z + rz);
    c.bounds.extend(Eigen::AlignedBox3d(p - Eigen::Vector3d::Constant(r), p + Eigen::Vector3d::Constant(r)));
  };
  for (const MeshDraw& d : mesh_draws) {
    Caster c;
    const GpuMesh& g = meshes[size_t(d.mesh)];
    c.convex = g.convex;
    const Eigen::Matrix4d M = d.model.cast<double>();
    if (!g.bbox.isEmpty())
      for (int i = 0; i < 8; ++i)
        add(c, (M * g.bbox.corner(Eigen::AlignedBox3d::CornerType(i)).homogeneous()).head<3>(), 0.0);
    casters.push_back(c);
  }
  for (const HullInstance& h : hulls) {
    Caster c;
    c.convex = true;
    add(c, Eigen::Vector3d(h.p0r0[0], h.p0r0[1], h.p0r0[2]), std::abs(double(h.p0r0[3])));
    add(c, Eigen::Vector3d(h.p1r1[0], h.p1r1[1], h.p1r1[2]), std::abs(double(h.p1r1[3])));
    casters.push_back(c);
  }
  if (!hair_draws.empty()) {
    Caster c;
    for (const HairVertex& v : hair_vertices)
      add(c, Eigen::Vector3d(v.pos[0], v.pos[1], v.pos[2]), std::abs(double(v.half_width)));
    casters.push_back(c);
  }
  const double size = double(std::max(f.shadow_size, 1));
  const double texel_world = std::max(f.frustum.texel_world, 1e-9);
  const double reach = (std::clamp(kMaxPenumbraMetres / texel_world, 2.0, 48.0) + 3.0) / size;
  const double dz = 2.0 * texel_world / std::max(f.frustum.depth_range, 1e-9) + 2.0 / 65535.0;
  const Eigen::Matrix4d to_screen = f.view_proj.cast<double>();
  const Eigen::Matrix4d from_light = L.inverse();
  const PixelRect all{0, 0, f.w, f.h};
  constexpr int kMargin = 2;  // pixels: rounding, and a pixel centre's coverage
  // The pixel rectangle of points, or the whole frame when one is behind the eye.
  const auto rectOf = [&](const auto& points) {
    double px0 = 1e30, py0 = 1e30, px1 = -1e30, py1 = -1e30;
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector4d c = to_screen * p.homogeneous();
      if (!(c.w() > 1e-6)) return all;
      const double x = (0.5 * c.x() / c.w() + 0.5) * f.w, y = (0.5 * c.y() / c.w() + 0.5) * f.h;
      px0 = std::min(px0, x), px1 = std::max(px1, x), py0 = std::min(py0, y), py1 = std::max(py1, y);
    }
    return PixelRect{int(std::floor(px0)) - kMargin, int(std::floor(py0)) - kMargin, int(std::ceil(px1)) + kMargin,
                     int(std::ceil(py1)) + kMargin} &
           all;
  };
  std::vector<Eigen::Vector3d> corners(8);
  for (size_t a = 0; a < casters.size(); ++a) {
    const Caster& A = casters[a];
    if (A.bounds.isEmpty()) continue;
    for (int i = 0; i < 8; ++i) corners[size_t(i)] = A.bounds.corner(Eigen::AlignedBox3d::CornerType(i));
    const PixelRect own = rectOf(corners);
    if (own.empty()) continue;
    if (!A.convex) {
      out.push_back(own);
      continue;
    }
    for (size_t b = 0; b < casters.size(); ++b) {
      const Caster& B = casters[b];
      if (b == a || B.bounds.isEmpty()) continue;
      const double bx0 = B.x0 - reach, bx1 = B.x1 + reach, by0 = B.y0 - reach, by1 = B.y1 + reach;
      const double bz0 = B.z0 - dz, bz1 = A.z1;
      if (bx1 < A.x0 || bx0 > A.x1 || by1 < A.y0 || by0 > A.y1 || bz0 >= bz1) continue;
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector4d n(2.0 * ((i & 1) ? bx1 : bx0) - 1.0, 2.0 * ((i & 2) ? by1 : by0) - 1.0,
                                2.0 * ((i & 4) ? bz1 : bz0) - 1.0, 1.0);
        const Eigen::Vector4d w = from_light * n;
        corners[size_t(i)] = w.head<3>() / w.w();
      }
      const PixelRect r = rectOf(corners) & own;
      if (!r.empty()) out.push_back(r);
    }
  }
  mergeRects(out, 4 * 16 * 16);
  // Worth it only when it spares a good part of the deferred shading's pixels (screenRects, where
  // it runs otherwise): the lit colour costs the objects pass a tone curve per fragment.
  std::vector<PixelRect> today;
  int64_t before = int64_t(f.w) * f.h, after = 0;
  if (screenRects(f.view_proj, f.w, f.h, today)) {
    before = 0;
    for (const PixelRect& r : today) before += r.area();
  }
  for (const PixelRect& r : out) after += r.area();
  return 4 * after < 3 * before;
}

// Meshes, hulls and hair into the main target, lit and shadowed; deferred (FramePlan::deferred),
// into the surface targets with their shadows left to deferredLightPass.
void Renderer::Impl::objectsPass(const FramePlan& f, RenderStats& st) {
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  shadow_marked = f.deferred && deferredRects(f, mark_rects);
  const GLuint mesh_prog = f.deferred ? prog_mesh_split : prog_mesh;
  const GLuint mesh_mat_prog = f.deferred ? prog_mesh_mat_split : prog_mesh_mat;
  const GLuint mesh_hair_prog = f.deferred ? prog_mesh_hair_split : prog_mesh_hair;
  const GLuint hair_only_prog = f.deferred ? prog_hair_only_split : prog_hair_only;
  const GLuint hull_prog = shadow_marked ? prog_hull_lit : f.deferred ? prog_hull_split : prog_hull;
  const GLuint hair_prog = f.deferred ? prog_hair_split : prog_hair;
  const GLuint mesh_lit_prog = shadow_marked ? prog_mesh_lit : 0;
  glClearColor(0, 0, 0, params.transparent ? 0 : 1);
  if (shadow_marked && f.clear_color) {  // the objects pass writes finished pixels into it
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
    glClear(GL_COLOR_BUFFER_BIT);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, f.deferred ? surf_fbo : msaa_fbo);
  if (f.deferred) {
    // The main colour target is the surface targets' fourth: the convex casters' lit colour, the
    // others' 0 (the deferred shading covers all their pixels).
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2, GL_COLOR_ATTACHMENT3};
    glDrawBuffers(shadow_marked ? 4 : 3, bufs);
  }
  glClear(!f.deferred && f.clear_color ? GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT : GL_DEPTH_BUFFER_BIT);
  bindShadowTextures(true);
  for (GLuint p : {mesh_prog, mesh_mat_prog, mesh_hair_prog, hair_only_prog, hull_prog, hair_prog, mesh_lit_prog}) {
    if (!p) continue;
    setFrameUniforms(p, f);
    glUniform4f(loc(p, "u_clipPlane"), 0.0f, 0.0f, f.clip_side, -f.clip_side * float(params.ground_height));
  }
  if (f.half_ground) glEnable(GL_CLIP_DISTANCE0);
  drawGeometry(mesh_prog, hull_prog, f.view_proj, false, -1, mesh_lit_prog);
  drawHairs(f.view_proj, false, f.light_dir, hair_prog);
  glDisable(GL_CLIP_DISTANCE0);
  st.draw_calls += int(hair_draws.size());
  for (const HairDraw& d : hair_draws) st.triangles += d.count / 3;
  st.draw_calls += int(mesh_draws.size()) + (hulls.empty() ? 0 : 1);
  for (const MeshDraw& d : mesh_draws) st.triangles += size_t(meshes[size_t(d.mesh)].index_count / 3);
  st.triangles += hulls.size() * hull_triangles;
}

// The shadow and the finished colour once per pixel of the objects' visible surface, from the
// surface targets into the main target.
void Renderer::Impl::deferredLightPass(const FramePlan& f, RenderStats& st) {
  glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
  if (f.clear_color && !shadow_marked) glClear(GL_COLOR_BUFFER_BIT);  // FramePlan::clear_color
  const GLuint targets[] = {surf_tex, key_tex, rest_tex};
  for (int i = 0; i < 3; ++i) {
    glActiveTexture(GLenum(GL_TEXTURE4 + i));
    glBindTexture(GL_TEXTURE_2D, targets[i]);
  }
  glActiveTexture(GL_TEXTURE0);
  for (GLuint p : {prog_deferred_class, prog_deferred}) {
    setFrameUniforms(p, f);
    glUniform1i(loc(p, "u_surface"), 4);
    glUniform1i(loc(p, "u_key"), 5);
    glUniform1i(loc(p, "u_rest"), 6);
  }
  // Two passes, each a full-screen triangle just short of the far plane (glDepthRange) with
  // depth test GREATER: it passes where an object is. The first finishes the pixels whose
  // shadow needs no filter (no key light, nothing above the surface, or the umbra:
  // shadowKnown()) and moves their depth to the triangle's, discarding the others; the second, the whole
  // shadowFactor(), then runs only where an object's depth is left: llvmpipe tests depth
  // before the shader (a discarding shader keeps the early test when it writes no stencil), so
  // the filter costs nothing where it is not needed. Just short of the far plane, so that the
  // background drawn after the objects at the far plane (without a ground) leaves them alone.
  glDepthRange(0.0, 1.0 - std::ldexp(1.0, -19));
  glDepthFunc(GL_GREATER);
  glBindVertexArray(empty_vao);
  // Marked (objectsPass): only over the rectangles where another caster can shadow a pixel; the
  // convex casters' pixels elsewhere hold their finished colour.
  const bool boxed = shadow_marked || screenRects(f.view_proj, f.w, f.h, rects);
  if (shadow_marked) rects = mark_rects;
  if (boxed) glEnable(GL_SCISSOR_TEST);
  for (GLuint p : {prog_deferred_class, prog_deferred}) {
    glUseProgram(p);
    glDepthMask(p == prog_deferred_class ? GL_TRUE : GL_FALSE);
    if (boxed) {
      for (const PixelRect& r : rects) {
        glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
        glDrawArrays(GL_TRIANGLES, 0, 3);
      }
    } else {
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
  }
  glDisable(GL_SCISSOR_TEST);
  glDepthRange(0.0, 1.0);
  glBindVertexArray(0);
  glDepthMask(GL_TRUE);
  for (int i = 0; i < 3; ++i) {  // they are render targets again next frame
    glActiveTexture(GLenum(GL_TEXTURE4 + i));
    glBindTexture(GL_TEXTURE_2D, 0);
  }
  glActiveTexture(GL_TEXTURE0);
  glDepthFunc(GL_LESS);
  st.draw_calls += 2;
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Debug lines

// Debug lines (the drag line, render.colliders) over the picture: no depth test.
void Renderer::Impl::linesPass(const FramePlan& f, RenderStats& st) {
  glDisable(GL_DEPTH_TEST);
  glUseProgram(prog_lines);
  setMat4(prog_lines, "u_viewProj", f.view_proj);
  glBindVertexArray(lines_vao);
  glBindBuffer(GL_ARRAY_BUFFER, lines_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(lines.size() * sizeof(LineVertex)), lines.data(), GL_STREAM_DRAW);
  glDrawArrays(GL_LINES, 0, GLsizei(lines.size()));
  glEnable(GL_DEPTH_TEST);
  glBindVertexArray(0);
  ++st.draw_calls;
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Anti-aliasing

// Into the output target: the MSAA resolve, or the post-process filter.
void Renderer::Impl::antiAliasPass(const FramePlan& f) {
  const int w = f.w, h = f.h;
  if (f.msaa) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo);
    glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    return;
  }
  // The filter classifies and filters only where an edge can be (postFilterRegions): inside the
  // screen rectangles of what was drawn (objects, hair, lines), grown by its reach, and of a box
  // only in bands along its edges and where it meets the ground or another box; the background
  // and the ground around them have no edges to smooth (the checker is box-filtered, the shadows
  // soft), nor has a box's flat face. The frame stays where it is and is filtered in place, from
  // a copy of the rectangles and of what the filter's taps reach around them (5 px: 4 along an
  // edge, and a texel of bilinear footprint), or of the whole frame when they are not bounded.
  const bool boxed = screenRects(f.view_proj, w, h, rects);
  if (!boxed) rects.assign(1, PixelRect{0, 0, w, h});
  // The shadow taps' reach, as groundShadowPass takes it (ground_shadow_reach).
  const int gs = std::max(64, shadow_size / kGroundShadowDivisor);
  const double ground_texel = frustum.texel_world * double(shadow_size) / double(gs);
  postFilterRegions(f, boxed, kMaxPenumbraMetres + 12.0 * frustum.texel_world + 3.0 * ground_texel, post_tris);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, post_src_fbo);
  constexpr int kReach = 6;
  for (const PixelRect& r : rects) {
    const int x0 = std::max(r.x0 - kReach, 0), y0 = std::max(r.y0 - kReach, 0);
    const int x1 = std::min(r.x1 + kReach, w), y1 = std::min(r.y1 + kReach, h);
    glBlitFramebuffer(x0, y0, x1, y1, x0, y0, x1, y1, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  output_fbo = msaa_fbo;  // its depth buffer is done with: the filter marks edges in it
  glBindFramebuffer(GL_FRAMEBUFFER, output_fbo);
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, post_src_tex);
  glActiveTexture(GL_TEXTURE0);
  for (GLuint p : {prog_post_class, prog_post}) {
    glUseProgram(p);
    glUniform1i(loc(p, "u_frame"), 3);
    glUniform2f(loc(p, "u_texel"), 1.0f / float(w), 1.0f / float(h));
  }
  // The regions' triangles in the debug lines' buffer (drawn by now). Two passes over them, all
  // at depth 0 (glDepthRange): the first writes no colour and discards the pixels without an
  // edge, so that only the edges take depth 0; the second, the filter, runs under depth test
  // EQUAL, which llvmpipe's early depth test limits to those pixels (llvmpipe runs both sides of
  // a shader's branches, but skips blocks the early test rejects). Where regions overlap, a pixel
  // is classified and filtered again from the same copy, with the same result. A pixel of the
  // objects exactly at depth 0 (on the near plane) would be filtered too: the filter passes
  // pixels without an edge through unchanged.
  glBindVertexArray(lines_vao);
  glBindBuffer(GL_ARRAY_BUFFER, lines_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(post_tris.size() * sizeof(LineVertex)), post_tris.data(), GL_STREAM_DRAW);
  const GLsizei n = GLsizei(post_tris.size());
  glEnable(GL_DEPTH_TEST);
  glDepthRange(0.0, 0.0);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_ALWAYS);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glUseProgram(prog_post_class);
  glDrawArrays(GL_TRIANGLES, 0, n);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_FALSE);
  glDepthFunc(GL_EQUAL);
  glUseProgram(prog_post);
  glDrawArrays(GL_TRIANGLES, 0, n);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  glDepthRange(0.0, 1.0);
  glBindVertexArray(0);
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, 0);  // the main pass renders into it next frame
  glActiveTexture(GL_TEXTURE0);
}

}  // namespace ponyhop

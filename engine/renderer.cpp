#include "engine/renderer.h"

#include <glad/gl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "engine/gl_context.h"
#include "engine/primitives.h"
#include "engine/shaders.h"

namespace ponyhop {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// The ground's shadow texture has shadow_size / this texels a side (renderer.cpp, endFrame).
constexpr int kGroundShadowDivisor = 4;
// The fewest texels a side resolutionMatchedShadowSize() gives a shadow map.
constexpr int kMinMatchedShadowSize = 512;

// Angular radius of the key light (rad) for the penumbra of the soft shadows.
constexpr double kKeyLightAngularRadius = 1.5 * 3.14159265358979 / 180.0;
// Widest penumbra (and blocker search radius) of the soft shadows, m; at least 2 texels, at most
// 48 (setCommonUniforms).
constexpr double kMaxPenumbraMetres = 0.03;

float srgbToLinear(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
Eigen::Vector3f srgbToLinear(const Eigen::Vector3f& c) {
  return {srgbToLinear(c.x()), srgbToLinear(c.y()), srgbToLinear(c.z())};
}

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei index_count = 0;
  Eigen::AlignedBox3d bbox;
  // With the file's materials (MeshData::colors): drawn by prog_mesh_mat, part by part.
  bool materials = false;
  // closedOrientation(): +1/-1 closed (back faces culled in both passes), 0 open (both sides drawn).
  int closed = 0;
  std::vector<MeshPart> parts;
  std::vector<GLuint> textures;
};

struct MeshDraw {
  int mesh;
  Eigen::Matrix4f model;
  Eigen::Matrix3f normal;
  Material material;
};

// Per-instance data of the hull (sphere/capsule) draw: matches the attributes of kCapsuleVS.
struct HullInstance {
  float p0r0[4];
  float p1r1[4];
  float color_spec[4];
  float shin_rim[2];
};

// One hair draw: a range of the frame's hair indices, another for the shadow pass
// (HairMesh::shadow_indices), and its shading constants.
struct HairDraw {
  size_t first = 0, count = 0;
  size_t shadow_first = 0, shadow_count = 0;
  HairShading shading;
};

struct LineVertex {
  float pos[3];
  float color[3];
};

// Orthographic light frustum fitted to a set of points, with texel snapping.
struct LightFrustum {
  Eigen::Matrix4d view_proj = Eigen::Matrix4d::Identity();
  double texel_world = 0.0;  // m per shadow texel
  double depth_range = 1.0;  // m between the near and far planes
};

Eigen::Matrix4d lookAlong(const Eigen::Vector3d& dir) {
  // Rotation-only view matrix of a camera at the origin looking along `dir` (z up when possible).
  Eigen::Vector3d f = dir.normalized();
  Eigen::Vector3d up = std::abs(f.z()) > 0.99 ? Eigen::Vector3d(0, 1, 0) : Eigen::Vector3d(0, 0, 1);
  Eigen::Vector3d s = f.cross(up).normalized();
  Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  return m;
}

Eigen::Matrix4d ortho(double l, double r, double b, double t, double n, double f) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = 2.0 / (r - l);
  m(1, 1) = 2.0 / (t - b);
  m(2, 2) = -2.0 / (f - n);
  m(0, 3) = -(r + l) / (r - l);
  m(1, 3) = -(t + b) / (t - b);
  m(2, 3) = -(f + n) / (f - n);
  return m;
}

// Fits the light's orthographic box to the casters and to their shadows on the ground: the points
// are the bounds' corners and those corners pushed along the light onto the ground (z = ground_z).
// The square extent
// is rounded up to steps of 2^(1/4) and the centre snapped to whole texels, so that a moving scene
// changes the shadow map's texel grid rarely and only by whole texels (no crawling edges).
LightFrustum fitLightFrustum(const Eigen::Vector3d& dir, const Eigen::AlignedBox3d& casters, int size,
                             double softness_texels, double ground_z) {
  LightFrustum lf;
  const Eigen::Matrix4d V = lookAlong(dir);
  const Eigen::Matrix3d R = V.block<3, 3>(0, 0);
  Eigen::AlignedBox3d ls;  // light space
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d c = casters.corner(Eigen::AlignedBox3d::CornerType(i));
    ls.extend(R * c);
    const double above = c.z() - ground_z;
    if (dir.z() < -1e-3 && above > 0.0) ls.extend(R * (c + dir * (above / -dir.z())));
  }
  double extent = std::max(ls.sizes().x(), ls.sizes().y());
  extent = std::max(extent, 1e-3);
  // Margin for the PCF kernel and the normal offset (a few texels).
  extent *= 1.0 + (4.0 + 2.0 * softness_texels) / double(size);
  extent = std::pow(2.0, std::ceil(std::log2(extent) * 4.0) / 4.0);
  const double texel = extent / double(size);
  Eigen::Vector2d center = 0.5 * (ls.min().head<2>() + ls.max().head<2>());
  center = (center / texel).array().round().matrix() * texel;
  const double depth_margin = 0.05 * std::max(ls.sizes().z(), extent) + 1e-3;
  const double n = -ls.max().z() - depth_margin, f = -ls.min().z() + depth_margin;
  const Eigen::Matrix4d P =
      ortho(center.x() - extent / 2, center.x() + extent / 2, center.y() - extent / 2, center.y() + extent / 2, n, f);
  lf.view_proj = P * V;
  lf.texel_world = texel;
  lf.depth_range = f - n;
  return lf;
}

// The shadow map's side for a frame (light.shadow_match; draft takes half): as many texels as the
// frame can show, at most `max_size`. A texel finer than a screen pixel adds nothing the picture
// can hold (the soft filter averages over several texels anyway), while every texel costs the
// clear, the casters' depth and the ground's shadow texture. The finest pixel is at the nearest
// point of the casters and of their shadows on the ground (a box's nearest depth is at a corner),
// where one pixel spans 2 z tan(fov / 2) / height metres; the side is the light frustum's extent
// at `max_size` over that, rounded up to a step of 2^(1/4) (few distinct sizes, each reallocation
// rare), and never below `min_size`: small frames keep the goldens' look (320x180) and thin parts
// keep their shadows. Stateless: a frame gets the same map whatever was drawn before it.
int resolutionMatchedShadowSize(const Camera& cam, int height, const Eigen::Vector3d& light_dir,
                                const Eigen::AlignedBox3d& casters, double ground_z, double extent, int min_size,
                                int max_size) {
  const Eigen::Vector3d fwd = (cam.target - cam.eye).normalized();
  double z = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d c = casters.corner(Eigen::AlignedBox3d::CornerType(i));
    z = std::min(z, (c - cam.eye).dot(fwd));
    const double above = c.z() - ground_z;
    if (light_dir.z() < -1e-3 && above > 0.0)
      z = std::min(z, (c + light_dir * (above / -light_dir.z()) - cam.eye).dot(fwd));
  }
  const double pixel = 2.0 * z * std::tan(0.5 * cam.fov * M_PI / 180.0) / double(std::max(height, 1));
  if (!(pixel > 0.0) || !std::isfinite(pixel)) return max_size;  // a caster at or behind the eye
  const double texels = extent / pixel;
  if (texels >= double(max_size)) return max_size;
  const int stepped = int(std::ceil(std::pow(2.0, std::ceil(std::log2(std::max(texels, 1.0)) * 4.0) / 4.0)));
  return std::clamp(stepped, std::min(min_size, max_size), max_size);
}

void unpremultiplyAlpha(std::vector<uint8_t>& rgba) {
  for (size_t i = 0; i + 3 < rgba.size(); i += 4) {
    const int a = rgba[i + 3];
    if (a == 0 || a == 255) continue;
    for (int c = 0; c < 3; ++c) rgba[i + size_t(c)] = uint8_t(std::min(255, (rgba[i + size_t(c)] * 255 + a / 2) / a));
  }
}

}  // namespace

struct Renderer::Impl {
  // Programs.
  GLuint prog_mesh = 0, prog_hull = 0, prog_ground = 0, prog_ground_shadow = 0, prog_lines = 0;
  GLuint prog_mesh_depth = 0, prog_hull_depth = 0, prog_post = 0, prog_bg = 0;
  GLuint prog_hair = 0, prog_hair_depth = 0;
  GLuint prog_mesh_mat = 0;
  std::vector<GLuint> programs;  // every program above, for the destructor
  // Deferred shading (single-sample targets with shadows): the lit programs writing the visible
  // surface and the two parts of its radiance (SPLIT_LIGHT), and the pass that shadows and
  // finishes each visible pixel once.
  GLuint prog_mesh_split = 0, prog_mesh_mat_split = 0, prog_hull_split = 0, prog_hair_split = 0;
  GLuint prog_deferred = 0, prog_deferred_class = 0;
  GLuint prog_ground_up = 0;            // the half-resolution ground, upsampled (kGroundUpFS)
  GLuint prog_ground_near = 0;          // kGroundFS where nothing fades (GROUND_NEAR)
  GLuint prog_ground_near_lit = 0;      // ... and nothing is shadowed (GROUND_LIT)
  GLuint prog_ground_shadow_class = 0;  // the ground shadow's first pass (shadowClass)
  GLuint prog_post_class = 0;           // the post filter's first pass (edge or not)
  // Static geometry.
  GLuint hull_vao = 0, hull_vbo = 0, hull_ebo = 0, hull_instances = 0;
  GLsizei hull_index_count = 0;
  // The coarser template the shadow pass draws the hulls with (the same instances).
  GLuint hull_shadow_vao = 0, hull_shadow_vbo = 0, hull_shadow_ebo = 0;
  GLsizei hull_shadow_index_count = 0;
  size_t hull_triangles = 0;
  GLuint empty_vao = 0;
  GLuint lines_vao = 0, lines_vbo = 0;
  GLuint hair_vao = 0, hair_vbo = 0, hair_ebo = 0;
  std::vector<GpuMesh> meshes;  // index = MeshHandle::id; vao == 0: released
  int box_mesh = -1;
  // Targets.
  // Main pass target: MSAA renderbuffers (samples > 1, antialias = msaa) or a single-sample colour
  // texture (read by the post-process filter, or directly without anti-aliasing).
  GLuint msaa_fbo = 0, msaa_color = 0, msaa_depth = 0, main_color_tex = 0;
  GLuint resolve_fbo = 0, resolve_color = 0;
  GLuint resolve_depth = 0;  // marks the pixels the post filter has an edge at
  GLuint output_fbo = 0;     // where the finished frame is: resolve_fbo; msaa_fbo without AA or filtered in place
  // The post filter over rectangles: a copy of them (and around them, as far as its taps reach)
  // that it reads while it writes the main target in place (endFrame).
  GLuint post_src_fbo = 0, post_src_tex = 0;
  bool target_post = false;
  // With a single-sample target: position + normal of the visible surface, and the key light's
  // part of its radiance before the shadow and the rest (kDeferredFS), sharing the main depth
  // buffer.
  GLuint surf_fbo = 0, surf_tex = 0, key_tex = 0, rest_tex = 0;
  // With a single-sample target: the ground (over the background) at half resolution.
  GLuint ground_lo_fbo = 0, ground_lo_tex = 0, ground_lo_depth = 0;
  GLuint ground_up_fbo = 0;  // main_color_tex without a depth buffer
  int ground_lo_w = 0, ground_lo_h = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;
  GLuint raw_depth_sampler = 0;                         // reads shadow_tex without comparison (blocker search)
  GLuint ground_shadow_fbo = 0, ground_shadow_tex = 0;  // R8, shadowFactor on the ground plane
  GLuint ground_shadow_depth = 0;                       // marks the texels that need the filter
  int ground_shadow_size = 0;
  // This frame's texels of the ground's shadow texture that are not 1 (lit) lie in this box
  // [x0, x1) x [y0, y1) (casterTexelBox); none when !ground_shadow_boxed.
  bool ground_shadow_boxed = false;
  int ground_shadow_box[4] = {0, 0, 0, 0};
  LightFrustum frustum;
  int target_w = 0, target_h = 0, target_samples = -1, shadow_size = 0;
  // The shadow filter's least radius in this frame's texels: light.shadow_softness texels of the
  // map shadow_size would have, unmatched (resolutionMatchedShadowSize), so that a matched map
  // blurs no wider than the full one.
  double softness_texels = 0.0;
  int max_samples = 1;
  // The frame being built.
  Camera camera;
  LightParams light;
  RenderParams params;
  bool have_shadow_bounds = false;
  Eigen::AlignedBox3d shadow_bounds;
  Eigen::AlignedBox3d draw_bounds;
  std::vector<Eigen::AlignedBox3d> part_bounds;  // one box per mesh, hull and hair draw (screenRects)
  std::vector<MeshDraw> mesh_draws;
  std::vector<HullInstance> hulls;
  std::vector<LineVertex> lines;
  std::vector<HairVertex> hair_vertices;
  std::vector<uint32_t> hair_indices;
  std::vector<HairDraw> hair_draws;
  bool in_frame = false;
  bool draft = false;  // this frame is RenderQuality::Draft
  // Per-pass timing (RenderStats): software rasterizers are timed with glFinish + the wall clock,
  // hardware GPUs with GL_TIME_ELAPSED queries, double-buffered and read one frame late.
  enum Pass { kShadowPass, kMainPass, kResolvePass, kPasses };
  bool software_gl = true;
  GLuint queries[2][kPasses] = {};
  int queries_pending[2] = {0, 0};  // bit p: pass p's query of that slot awaits reading
  int query_frame = 0;
  Clock::time_point pass_t0;
  void beginPass(Pass p);
  void endPass(Pass p, RenderStats& st);
  void collectGpuTimes(RenderStats& st);

  void ensureTargets(int w, int h, int samples, bool post);
  struct PixelRect {
    int x0, y0, x1, y1;  // [x0, x1) x [y0, y1)
    int64_t area() const { return int64_t(x1 - x0) * (y1 - y0); }
  };
  bool screenRects(const Eigen::Matrix4f& view_proj, int w, int h, std::vector<PixelRect>& rects) const;
  std::vector<PixelRect> rects;  // scratch of endFrame (kept: no allocation per frame)
  bool casterTexelBox(const Eigen::Matrix4d& light_vp, double margin_m, int size, int box[4]) const;
  // The pixel rectangle (of a w x h viewport) outside which the ground is lit: its shadow texture
  // reads 1 there. False: none (nothing shadowed); `whole` set when it cannot be bounded.
  bool groundShadowRect(const Eigen::Matrix4f& view_proj, int w, int h, PixelRect& rect, bool& whole) const;
  void ensureShadowMap(int size);
  void ensureGroundShadow(int size);
  void bindShadowTextures(bool ground_shadow);  // units 0, 1: the shadow map; 2: the ground's
  void setCommonUniforms(GLuint prog, const Eigen::Matrix4f& view_proj, const Eigen::Matrix4f& light_vp,
                         float normal_offset, bool shadows_on);
  void drawGeometry(GLuint mesh_prog, GLuint hull_prog, const Eigen::Matrix4f& view_proj, bool depth_only);
  // prog: the program for the main pass's camera-facing ribbons (0: prog_hair).
  void drawHairs(const Eigen::Matrix4f& view_proj, bool depth_only, const Eigen::Vector3d& light_dir, GLuint prog = 0);
  void drawMaterialMeshes(GLuint prog);
};

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

// The bound 2D texture: bilinear, clamped at its edges.
static void linearClampToEdge() {
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

static GLint loc(GLuint prog, const char* name) { return glGetUniformLocation(prog, name); }
static void setMat4(GLuint prog, const char* name, const Eigen::Matrix4f& m) {
  glUniformMatrix4fv(loc(prog, name), 1, GL_FALSE, m.data());  // Eigen is column-major, as GL
}
static void setVec3(GLuint prog, const char* name, const Eigen::Vector3f& v) {
  glUniform3f(loc(prog, name), v.x(), v.y(), v.z());
}

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}

Renderer::~Renderer() {
  if (!glDeleteProgram) return;  // GL never loaded: nothing was created
  Impl& I = *impl_;
  for (GLuint p : I.programs)
    if (p) glDeleteProgram(p);
  for (int i = 0; i < int(I.meshes.size()); ++i) release(MeshHandle{i});
  GLuint vaos[] = {I.hull_vao, I.hull_shadow_vao, I.empty_vao, I.lines_vao, I.hair_vao};
  glDeleteVertexArrays(5, vaos);
  GLuint bufs[] = {I.hull_vbo,       I.hull_ebo,  I.hull_shadow_vbo, I.hull_shadow_ebo,
                   I.hull_instances, I.lines_vbo, I.hair_vbo,        I.hair_ebo};
  glDeleteBuffers(8, bufs);
  GLuint fbos[] = {I.msaa_fbo, I.resolve_fbo,   I.shadow_fbo,    I.ground_shadow_fbo,
                   I.surf_fbo, I.ground_lo_fbo, I.ground_up_fbo, I.post_src_fbo};
  glDeleteFramebuffers(8, fbos);
  GLuint rbs[] = {I.msaa_color,          I.msaa_depth,    I.resolve_color,
                  I.ground_shadow_depth, I.resolve_depth, I.ground_lo_depth};
  glDeleteRenderbuffers(6, rbs);
  if (I.main_color_tex) glDeleteTextures(1, &I.main_color_tex);
  for (GLuint t : {I.surf_tex, I.key_tex, I.rest_tex, I.ground_lo_tex, I.post_src_tex})
    if (t) glDeleteTextures(1, &t);
  if (I.shadow_tex) glDeleteTextures(1, &I.shadow_tex);
  if (I.ground_shadow_tex) glDeleteTextures(1, &I.ground_shadow_tex);
  if (I.raw_depth_sampler) glDeleteSamplers(1, &I.raw_depth_sampler);
  if (I.queries[0][0]) glDeleteQueries(2 * Impl::kPasses, &I.queries[0][0]);
}

bool Renderer::init(std::string* err) {
  if (!glCreateProgram) {
    if (err) *err = "Renderer::init: GL is not loaded (call loadGL or create a HeadlessContext first)";
    return false;
  }
  Impl& I = *impl_;
  using namespace shaders;
  struct P {
    GLuint* out;
    const char* name;
    const char* vs;
    const char* fs;
    const char* defines = nullptr;
  };
  const P progs[] = {
      {&I.prog_mesh, "mesh", kMeshVS, kLitFS},
      {&I.prog_mesh_mat, "mesh with materials", kMeshMatVS, kMeshMatFS},
      {&I.prog_hull, "hull", kCapsuleVS, kLitFS},
      {&I.prog_ground, "ground", kGroundVS, kGroundFS},
      {&I.prog_ground_shadow, "ground shadow", kFullscreenVS, kGroundShadowFS},
      {&I.prog_lines, "lines", kLinesVS, kLinesFS},
      {&I.prog_mesh_depth, "mesh depth", kMeshVS, kDepthFS},
      {&I.prog_hull_depth, "hull depth", kCapsuleVS, kDepthFS},
      {&I.prog_post, "post AA", kFullscreenVS, kPostAaFS},
      {&I.prog_bg, "background", kFullscreenVS, kBackgroundFS},
      {&I.prog_hair, "hair", kHairVS, kHairFS},
      {&I.prog_hair_depth, "hair depth", kHairVS, kDepthFS},
      {&I.prog_mesh_split, "mesh (deferred)", kMeshVS, kLitFS, kSplitLightDefine},
      {&I.prog_mesh_mat_split, "mesh with materials (deferred)", kMeshMatVS, kMeshMatFS, kSplitLightDefine},
      {&I.prog_hull_split, "hull (deferred)", kCapsuleVS, kLitFS, kSplitLightDefine},
      {&I.prog_hair_split, "hair (deferred)", kHairVS, kHairFS, kSplitLightDefine},
      {&I.prog_deferred, "deferred shading", kFullscreenVS, kDeferredFS},
      {&I.prog_deferred_class, "deferred shading (lit and unlit)", kFullscreenVS, kDeferredFS, kShadowClassifyDefine},
      {&I.prog_ground_up, "ground (upsampled)", kGroundUpVS, kGroundUpFS},
      {&I.prog_ground_near, "ground (near)", kGroundVS, kGroundFS, kGroundNearDefine},
      {&I.prog_ground_near_lit, "ground (near, lit)", kGroundVS, kGroundFS, kGroundNearLitDefine},
      {&I.prog_ground_shadow_class, "ground shadow (classify)", kFullscreenVS, kGroundShadowFS, kShadowClassifyDefine},
      {&I.prog_post_class, "post AA (edges)", kFullscreenVS, kPostAaFS, kPostEdgesDefine}};
  for (const P& p : progs) {
    if (!(*p.out = buildProgram(p.name, p.vs, p.fs, err, p.defines))) return false;
    I.programs.push_back(*p.out);
  }

  // Hull template: 24 slices x 8 rings per cap (768 triangles); instanced. Smooth at the sizes
  // links have on screen (tens of pixels); the normals are exact, only the outline is polygonal.
  // The shadow pass draws a coarser one, 16 slices x 4 rings (256 triangles): llvmpipe's cost
  // there is per triangle, and its outline stays within 2 % of the radius of the true one (about
  // a shadow texel for the hopper's body), inside it, so that no surface shadows itself.
  glGenBuffers(1, &I.hull_instances);
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
    glBindBuffer(GL_ARRAY_BUFFER, I.hull_instances);
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
  const size_t hull_indices = makeHullVao(24, 8, I.hull_vao, I.hull_vbo, I.hull_ebo);
  I.hull_index_count = GLsizei(hull_indices);
  I.hull_triangles = hull_indices / 3;
  I.hull_shadow_index_count = GLsizei(makeHullVao(16, 4, I.hull_shadow_vao, I.hull_shadow_vbo, I.hull_shadow_ebo));

  glGenSamplers(1, &I.raw_depth_sampler);
  glSamplerParameteri(I.raw_depth_sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glSamplerParameteri(I.raw_depth_sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glSamplerParameteri(I.raw_depth_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glSamplerParameteri(I.raw_depth_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glSamplerParameteri(I.raw_depth_sampler, GL_TEXTURE_COMPARE_MODE, GL_NONE);

  glGenVertexArrays(1, &I.empty_vao);  // core profile: a draw needs a VAO even without attributes

  glGenVertexArrays(1, &I.lines_vao);
  glBindVertexArray(I.lines_vao);
  glGenBuffers(1, &I.lines_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, I.lines_vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(LineVertex), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(LineVertex),
                        reinterpret_cast<const void*>(offsetof(LineVertex, color)));

  // Hair: positions, tangents, normals, colours and (half width, occlusion) per vertex, streamed.
  glGenVertexArrays(1, &I.hair_vao);
  glBindVertexArray(I.hair_vao);
  glGenBuffers(1, &I.hair_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, I.hair_vbo);
  glGenBuffers(1, &I.hair_ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, I.hair_ebo);
  const size_t hair_attr[] = {offsetof(HairVertex, pos), offsetof(HairVertex, tangent), offsetof(HairVertex, normal),
                              offsetof(HairVertex, color), offsetof(HairVertex, half_width)};
  for (GLuint a = 0; a < 5; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, a == 4 ? 2 : 3, GL_FLOAT, GL_FALSE, sizeof(HairVertex),
                          reinterpret_cast<const void*>(hair_attr[a]));
  }
  glBindVertexArray(0);

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

// A mesh with colours: position, normal, colour, uv (12 floats a vertex), and its textures.
static void uploadWithMaterials(const MeshData& m, GpuMesh& g) {
  std::vector<float> v;
  v.reserve(m.positions.size() * 12);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Eigen::Vector3f n = i < m.normals.size() ? m.normals[i] : Eigen::Vector3f(0, 0, 1);
    const Eigen::Vector4f c = i < m.colors.size() ? m.colors[i] : Eigen::Vector4f(1, 1, 1, 1);
    const Eigen::Vector2f t = i < m.uvs.size() ? m.uvs[i] : Eigen::Vector2f(0, 0);
    v.insert(v.end(), {m.positions[i].x(), m.positions[i].y(), m.positions[i].z(), n.x(), n.y(), n.z(), c.x(), c.y(),
                       c.z(), c.w(), t.x(), t.y()});
  }
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
  const GLsizei stride = 12 * sizeof(float);
  const int sizes[4] = {3, 3, 4, 2}, offsets[4] = {0, 3, 6, 10};
  for (GLuint a = 0; a < 4; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, sizes[a], GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<const void*>(size_t(offsets[a]) * sizeof(float)));
  }
  g.materials = true;
  g.parts = m.parts.empty() ? std::vector<MeshPart>{MeshPart{0, uint32_t(m.indices.size()), -1}} : m.parts;
  for (const MeshTexture& img : m.textures) {
    GLuint tex = 0;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, img.width, img.height, 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 img.rgba.data());
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    g.textures.push_back(tex);
  }
  glBindTexture(GL_TEXTURE_2D, 0);
}

MeshHandle Renderer::upload(const MeshData& m) {
  Impl& I = *impl_;
  GpuMesh g;
  g.closed = closedOrientation(m);
  if (!m.colors.empty()) {
    uploadWithMaterials(m, g);
    glGenBuffers(1, &g.ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(m.indices.size() * sizeof(uint32_t)), m.indices.data(),
                 GL_STATIC_DRAW);
    glBindVertexArray(0);
    g.index_count = GLsizei(m.indices.size());
    for (const auto& p : m.positions) g.bbox.extend(p.cast<double>());
    I.meshes.push_back(g);
    return MeshHandle{int(I.meshes.size()) - 1};
  }
  std::vector<float> v;
  v.reserve(m.positions.size() * 6);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Eigen::Vector3f n = i < m.normals.size() ? m.normals[i] : Eigen::Vector3f(0, 0, 1);
    v.insert(v.end(), {m.positions[i].x(), m.positions[i].y(), m.positions[i].z(), n.x(), n.y(), n.z()});
  }
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(v.size() * sizeof(float)), v.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<const void*>(3 * sizeof(float)));
  glGenBuffers(1, &g.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(m.indices.size() * sizeof(uint32_t)), m.indices.data(),
               GL_STATIC_DRAW);
  glBindVertexArray(0);
  g.index_count = GLsizei(m.indices.size());
  for (const auto& p : m.positions) g.bbox.extend(p.cast<double>());
  I.meshes.push_back(g);
  return MeshHandle{int(I.meshes.size()) - 1};
}

void Renderer::release(MeshHandle h) {
  Impl& I = *impl_;
  if (h.id < 0 || h.id >= int(I.meshes.size()) || I.meshes[size_t(h.id)].vao == 0) return;
  GpuMesh& g = I.meshes[size_t(h.id)];
  glDeleteVertexArrays(1, &g.vao);
  glDeleteBuffers(1, &g.vbo);
  glDeleteBuffers(1, &g.ebo);
  if (!g.textures.empty()) glDeleteTextures(GLsizei(g.textures.size()), g.textures.data());
  g = GpuMesh{};
}

void Renderer::beginFrame(const Camera& camera, const LightParams& light, const RenderParams& params) {
  Impl& I = *impl_;
  I.camera = camera;
  I.light = light;
  I.params = params;
  I.have_shadow_bounds = false;
  I.draw_bounds.setEmpty();
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

void Renderer::drawMesh(MeshHandle h, const Eigen::Affine3d& model, const Material& m) {
  Impl& I = *impl_;
  if (h.id < 0 || h.id >= int(I.meshes.size()) || I.meshes[size_t(h.id)].vao == 0) return;
  MeshDraw d;
  d.mesh = h.id;
  d.model = model.matrix().cast<float>();
  d.normal = model.linear().inverse().transpose().cast<float>();
  d.material = m;
  I.mesh_draws.push_back(d);
  I.part_bounds.push_back(transformedBounds(model, I.meshes[size_t(h.id)].bbox));
  I.draw_bounds.extend(I.part_bounds.back());
}

void Renderer::drawBox(const Eigen::Affine3d& pose, const Eigen::Vector3d& half, const Material& m) {
  Eigen::Affine3d T = pose;
  T.linear() = pose.linear() * half.asDiagonal();
  drawMesh(MeshHandle{impl_->box_mesh}, T, m);
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

void Renderer::drawLines(const std::vector<DebugLine>& lines) {
  for (const DebugLine& l : lines) drawLine(l.a, l.b, l.color);
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
  if (post) {
    if (!post_src_fbo) {
      glGenFramebuffers(1, &post_src_fbo);
      glGenTextures(1, &post_src_tex);
    }
    glBindTexture(GL_TEXTURE_2D, post_src_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    linearClampToEdge();
    glBindFramebuffer(GL_FRAMEBUFFER, post_src_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, post_src_tex, 0);
  }
  if (samples == 1) {
    if (!surf_fbo) {
      glGenFramebuffers(1, &surf_fbo);
      glGenTextures(1, &surf_tex);
      glGenTextures(1, &key_tex);
      glGenTextures(1, &rest_tex);
    }
    // Full float: the shadow search sees exactly the position the forward shader has, and the
    // radiance is combined as the forward shader combines it.
    for (GLuint t : {surf_tex, key_tex, rest_tex}) {
      glBindTexture(GL_TEXTURE_2D, t);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, surf_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, surf_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, key_tex, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, rest_tex, 0);
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
  }
  target_w = w;
  target_h = h;
  target_samples = samples;
  target_post = post;
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
  // pass and every lookup are cheaper (one core, hopper at 1280x720: 15.9 -> 14.9 ms a frame).
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

// Meshes with their file's materials (main pass): one draw per part, its texture on unit 2.
void Renderer::Impl::drawMaterialMeshes(GLuint p) {
  bool used = false;
  for (const MeshDraw& d : mesh_draws) {
    const GpuMesh& g = meshes[size_t(d.mesh)];
    if (!g.materials) continue;
    if (!used) {
      glUseProgram(p);
      glUniform1i(loc(p, "u_baseTex"), 2);
      used = true;
    }
    glUniformMatrix4fv(loc(p, "u_model"), 1, GL_FALSE, d.model.data());
    glUniformMatrix3fv(loc(p, "u_normalMat"), 1, GL_FALSE, d.normal.data());
    const Eigen::Vector3f c = srgbToLinear(d.material.color);
    glUniform4f(loc(p, "u_colorSpec"), c.x(), c.y(), c.z(), d.material.specular);
    glUniform2f(loc(p, "u_shinRim"), d.material.shininess, d.material.rim);
    glBindVertexArray(g.vao);
    cullFor(g, d.model);
    for (const MeshPart& part : g.parts) {
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

void Renderer::Impl::drawGeometry(GLuint mesh_prog, GLuint hull_prog, const Eigen::Matrix4f& view_proj,
                                  bool depth_only) {
  if (!mesh_draws.empty()) {
    glUseProgram(mesh_prog);
    if (depth_only) setMat4(mesh_prog, "u_viewProj", view_proj);
    const GLint l_model = loc(mesh_prog, "u_model"), l_normal = loc(mesh_prog, "u_normalMat"),
                l_cs = loc(mesh_prog, "u_colorSpec"), l_sr = loc(mesh_prog, "u_shinRim");
    for (const MeshDraw& d : mesh_draws) {
      const GpuMesh& g = meshes[size_t(d.mesh)];
      if (g.materials && !depth_only) continue;  // below, with their own program
      glUniformMatrix4fv(l_model, 1, GL_FALSE, d.model.data());
      glUniformMatrix3fv(l_normal, 1, GL_FALSE, d.normal.data());
      const Eigen::Vector3f c = srgbToLinear(d.material.color);
      glUniform4f(l_cs, c.x(), c.y(), c.z(), d.material.specular);
      glUniform2f(l_sr, d.material.shininess, d.material.rim);
      glBindVertexArray(g.vao);
      cullFor(g, d.model);
      glDrawElements(GL_TRIANGLES, g.index_count, GL_UNSIGNED_INT, nullptr);
    }
    glDisable(GL_CULL_FACE);
    glCullFace(GL_BACK);
  }
  if (!depth_only) drawMaterialMeshes(mesh_prog == prog_mesh_split ? prog_mesh_mat_split : prog_mesh_mat);
  if (!hulls.empty()) {
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

// The pixel rectangles that the draw list and the debug lines cover in the main pass, each grown
// by the post filter's reach (its taps go 4 px along an edge): one per draw (its bounding box,
// projected), merged while a merge adds no more pixels than the two overlap or than a few 16x16
// blocks. The full-screen passes that only matter where an object is (the deferred shading, the
// post filter) run scissored to each: llvmpipe pays for every block a triangle covers, even where
// the early depth test then rejects it, and a hopper's body, leg and hair fill a third of their
// common box. False when they cover nearly the whole frame anyway, or a point is behind the eye
// (its projection is not bounded).
bool Renderer::Impl::screenRects(const Eigen::Matrix4f& view_proj, int w, int h, std::vector<PixelRect>& out) const {
  out.clear();
  if (draw_bounds.isEmpty() && lines.empty()) return false;
  constexpr int kReach = 6;
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  const auto add = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector4f c = view_proj * Eigen::Vector4f(float(p.x()), float(p.y()), float(p.z()), 1.0f);
    if (!(c.w() > 1e-6f)) return false;
    const double x = (0.5 * c.x() / c.w() + 0.5) * w, y = (0.5 * c.y() / c.w() + 0.5) * h;
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    return true;
  };
  const auto emit = [&] {
    const PixelRect r{std::clamp(int(std::floor(x0)) - kReach, 0, w), std::clamp(int(std::floor(y0)) - kReach, 0, h),
                      std::clamp(int(std::ceil(x1)) + kReach, 0, w), std::clamp(int(std::ceil(y1)) + kReach, 0, h)};
    if (r.x1 > r.x0 && r.y1 > r.y0) out.push_back(r);
    x0 = y0 = 1e30;
    x1 = y1 = -1e30;
  };
  // Many draws (a long chain of links): their union, as one.
  const bool one = part_bounds.size() > 64;
  const Eigen::AlignedBox3d* parts = one ? &draw_bounds : part_bounds.data();
  for (size_t k = 0, n = one ? 1 : part_bounds.size(); k < n; ++k) {
    const Eigen::AlignedBox3d& b = parts[k];
    if (b.isEmpty()) continue;
    for (int i = 0; i < 8; ++i)
      if (!add(b.corner(Eigen::AlignedBox3d::CornerType(i)))) return false;
    emit();
  }
  if (!lines.empty()) {
    for (const LineVertex& v : lines)
      if (!add(Eigen::Vector3d(v.pos[0], v.pos[1], v.pos[2]))) return false;
    emit();
  }
  const auto unite = [](const PixelRect& a, const PixelRect& b) {
    return PixelRect{std::min(a.x0, b.x0), std::min(a.y0, b.y0), std::max(a.x1, b.x1), std::max(a.y1, b.y1)};
  };
  const auto overlap = [](const PixelRect& a, const PixelRect& b) {
    const int64_t dx = std::min(a.x1, b.x1) - std::max(a.x0, b.x0), dy = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
    return dx > 0 && dy > 0 ? dx * dy : int64_t(0);
  };
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < out.size() && !merged; ++i)
      for (size_t j = i + 1; j < out.size() && !merged; ++j) {
        const PixelRect u = unite(out[i], out[j]);
        // Merged when the union adds no more pixels than the pair shades twice, or than 8 blocks.
        if (u.area() - (out[i].area() + out[j].area() - overlap(out[i], out[j])) <=
            std::max<int64_t>(overlap(out[i], out[j]), 8 * 256)) {
          out[i] = u;
          out.erase(out.begin() + std::ptrdiff_t(j));
          merged = true;
        }
      }
  }
  int64_t covered = 0;
  for (const PixelRect& r : out) covered += r.area();
  return !out.empty() && covered < int64_t(w) * h * 9 / 10;  // else: no gain
}

// The texel box [x0, x1) x [y0, y1) of a size x size texture over the light's square that holds
// everything drawn into the shadow map, seen along the light, grown by `margin_m` metres: meshes
// by their transformed bounding boxes, hulls by their spheres, hair by its vertices and ribbon
// half widths. False when nothing casts.
bool Renderer::Impl::casterTexelBox(const Eigen::Matrix4d& light_vp, double margin_m, int size, int box[4]) const {
  // For the orthographic light, light-space x and y are affine in the point and metres map to
  // the same number of texels on both axes.
  const Eigen::Matrix<double, 2, 4> A = light_vp.topRows<2>() * (0.5 * size);
  const double per_m = A.block<1, 3>(0, 0).norm();
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  const auto add = [&](const Eigen::Vector3d& p, double r) {
    const Eigen::Vector2d t = A.leftCols<3>() * p + A.col(3) + Eigen::Vector2d::Constant(0.5 * size);
    const double rt = r * per_m;
    x0 = std::min(x0, t.x() - rt);
    x1 = std::max(x1, t.x() + rt);
    y0 = std::min(y0, t.y() - rt);
    y1 = std::max(y1, t.y() + rt);
  };
  for (const MeshDraw& d : mesh_draws) {
    const Eigen::AlignedBox3d& b = meshes[size_t(d.mesh)].bbox;
    if (b.isEmpty()) continue;
    const Eigen::Matrix4d M = d.model.cast<double>();
    for (int i = 0; i < 8; ++i) add((M * b.corner(Eigen::AlignedBox3d::CornerType(i)).homogeneous()).head<3>(), 0.0);
  }
  for (const HullInstance& h : hulls) {
    add(Eigen::Vector3d(h.p0r0[0], h.p0r0[1], h.p0r0[2]), std::abs(double(h.p0r0[3])));
    add(Eigen::Vector3d(h.p1r1[0], h.p1r1[1], h.p1r1[2]), std::abs(double(h.p1r1[3])));
  }
  const double min_half = 0.5 * frustum.texel_world;  // drawHairs' minimum half width in this pass
  for (const HairVertex& v : hair_vertices)
    add(Eigen::Vector3d(v.pos[0], v.pos[1], v.pos[2]), std::max(std::abs(double(v.half_width)), min_half));
  if (x0 > x1) return false;
  const double m = margin_m * per_m;
  box[0] = std::clamp(int(std::floor(x0 - m)), 0, size);
  box[1] = std::clamp(int(std::floor(y0 - m)), 0, size);
  box[2] = std::clamp(int(std::ceil(x1 + m)), 0, size);
  box[3] = std::clamp(int(std::ceil(y1 + m)), 0, size);
  return box[2] > box[0] && box[3] > box[1];
}

bool Renderer::Impl::groundShadowRect(const Eigen::Matrix4f& view_proj, int w, int h, PixelRect& rect,
                                      bool& whole) const {
  whole = false;
  if (!ground_shadow_boxed || ground_shadow_size <= 0) return false;
  // The box's corners, a texel further out (the bilinear footprint), on the ground: the light ray
  // through each (as kGroundShadowFS finds it) meets the plane there.
  const Eigen::Matrix4d inv = frustum.view_proj.inverse();
  const double gs = double(ground_shadow_size), g = params.ground_height;
  const double xs[2] = {double(ground_shadow_box[0] - 1), double(ground_shadow_box[2] + 1)};
  const double ys[2] = {double(ground_shadow_box[1] - 1), double(ground_shadow_box[3] + 1)};
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  for (double tx : xs)
    for (double ty : ys) {
      const Eigen::Vector2d ndc(tx / gs * 2.0 - 1.0, ty / gs * 2.0 - 1.0);
      const Eigen::Vector4d a4 = inv * Eigen::Vector4d(ndc.x(), ndc.y(), -1.0, 1.0);
      const Eigen::Vector4d b4 = inv * Eigen::Vector4d(ndc.x(), ndc.y(), 1.0, 1.0);
      const Eigen::Vector3d a = a4.head<3>() / a4.w(), b = b4.head<3>() / b4.w();
      if (std::abs(b.z() - a.z()) < 1e-12) return whole = true;
      const Eigen::Vector3d P = a + (b - a) * ((g - a.z()) / (b.z() - a.z()));
      const Eigen::Vector4d c = view_proj.cast<double>() * P.homogeneous();
      if (c.w() < 1e-6) return whole = true;  // behind the eye: not bounded on screen
      const double px = (c.x() / c.w() * 0.5 + 0.5) * w, py = (c.y() / c.w() * 0.5 + 0.5) * h;
      x0 = std::min(x0, px);
      x1 = std::max(x1, px);
      y0 = std::min(y0, py);
      y1 = std::max(y1, py);
    }
  rect.x0 = std::clamp(int(std::floor(x0)) - 1, 0, w);
  rect.y0 = std::clamp(int(std::floor(y0)) - 1, 0, h);
  rect.x1 = std::clamp(int(std::ceil(x1)) + 1, 0, w);
  rect.y1 = std::clamp(int(std::ceil(y1)) + 1, 0, h);
  return rect.x1 > rect.x0 && rect.y1 > rect.y0;
}

// A full-screen program in two passes over the bound target, whose depth buffer is scratch:
// `first` writes the pixels it can decide and depth 0 at the others (gl_FragDepth); `second`, the
// costly one, then runs under the far-plane triangle with depth test GREATER, on those pixels
// only. llvmpipe runs both sides of a shader's branches, but its early depth test does skip
// blocks before shading. `first` = 0: `second` alone, everywhere. Leaves the depth test on with
// LESS and depth writes on.
static void drawFullscreenTwoPass(GLuint vao, GLuint first, GLuint second) {
  glBindVertexArray(vao);
  glEnable(GL_DEPTH_TEST);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_ALWAYS);
  if (first) {
    glUseProgram(first);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthFunc(GL_GREATER);
  }
  glDepthMask(GL_FALSE);
  glUseProgram(second);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
  glBindVertexArray(0);
}

void Renderer::endFrame() {
  Impl& I = *impl_;
  const auto t0 = Clock::now();
  const int w = std::clamp(I.params.width, 1, 16384), h = std::clamp(I.params.height, 1, 16384);
  // Quality: draft drops anti-aliasing and takes a half-size shadow map (512 at the default 1024)
  // with a plain filter.
  const bool draft = I.params.quality == RenderQuality::Draft;
  const bool aa = !draft && I.params.samples > 1;
  const bool msaa = aa && I.params.antialias == AntiAlias::Msaa;
  const bool post = aa && !msaa;
  const int samples = msaa ? std::clamp(I.params.samples, 1, std::max(I.max_samples, 1)) : 1;
  I.ensureTargets(w, h, samples, post);
  I.draft = draft;
  width_ = w;
  height_ = h;
  stats_ = RenderStats{};
  stats_.samples = samples;
  stats_.post_aa = post;
  stats_.draft = draft;
  I.collectGpuTimes(stats_);

  // Upload this frame's instance data once; both passes use it.
  if (!I.hulls.empty()) {
    glBindBuffer(GL_ARRAY_BUFFER, I.hull_instances);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(I.hulls.size() * sizeof(HullInstance)), I.hulls.data(), GL_STREAM_DRAW);
  }
  if (!I.hair_draws.empty()) {
    glBindVertexArray(I.hair_vao);
    glBindBuffer(GL_ARRAY_BUFFER, I.hair_vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(I.hair_vertices.size() * sizeof(HairVertex)), I.hair_vertices.data(),
                 GL_STREAM_DRAW);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(I.hair_indices.size() * sizeof(uint32_t)), I.hair_indices.data(),
                 GL_STREAM_DRAW);
    glBindVertexArray(0);
  }

  // --- Shadow pass: depth of the casters seen from the key light. ---
  const Eigen::AlignedBox3d casters = I.have_shadow_bounds ? I.shadow_bounds : I.draw_bounds;
  Eigen::Vector3d ld = I.light.direction;
  if (ld.norm() < 1e-9) ld = Eigen::Vector3d(-0.5, 0.6, -1.0);
  ld.normalize();
  const bool shadows_on = !casters.isEmpty() && I.light.intensity > 0.0;
  I.ground_shadow_boxed = false;
  LightFrustum lf;
  if (shadows_on) {
    I.beginPass(Impl::kShadowPass);
    const int max_size = std::clamp(I.light.shadow_size, 64, 8192);
    const double extent =
        fitLightFrustum(ld, casters, max_size, I.light.shadow_softness, I.params.ground_height).texel_world *
        double(max_size);
    // Not with hair: a strand is thinner than a texel (drawn a texel wide), and its shadow is the
    // share of texels its depth covers, which depends on the texel's size whatever the pixel's
    // (the chain's shadow on the ground at 1920x1080 came out lighter and grainy on a map of 609
    // texels, whose texels were still a tenth of a pixel there).
    const bool match = I.light.shadow_match && I.hair_draws.empty();
    const int size = !match ? max_size
                            : resolutionMatchedShadowSize(I.camera, h, ld, casters, I.params.ground_height, extent,
                                                          kMinMatchedShadowSize, max_size);
    I.ensureShadowMap(draft ? std::max(256, size / 2) : size);
    stats_.shadow_size = I.shadow_size;
    const int unmatched = draft ? std::max(256, max_size / 2) : max_size;
    // (at most 8 texels, the widest the margins around the casters allow: only a shadow_size
    // above 4096 matched down to 512 reaches it)
    I.softness_texels =
        std::min(std::clamp(I.light.shadow_softness, 0.0, 8.0) * double(unmatched) / double(I.shadow_size), 8.0);
    lf = fitLightFrustum(ld, casters, I.shadow_size, I.softness_texels, I.params.ground_height);
    I.frustum = lf;
    glBindFramebuffer(GL_FRAMEBUFFER, I.shadow_fbo);
    glViewport(0, 0, I.shadow_size, I.shadow_size);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glDisable(GL_CULL_FACE);  // open meshes cast from both sides (closed ones cull their back faces)
    // Slope-scaled bias in the depth pass (steep surfaces need more), plus the small normal offset
    // at lookup in the shader: together no acne, and the offset is too small to detach contact
    // shadows (no peter-panning).
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.5f, 2.0f);
    I.drawGeometry(I.prog_mesh_depth, I.prog_hull_depth, lf.view_proj.cast<float>(), true);
    I.drawHairs(lf.view_proj.cast<float>(), true, ld);
    glDisable(GL_POLYGON_OFFSET_FILL);
    if (I.params.ground) {
      // The ground's shadow once per frame into a texture over the shadow map's square, instead of
      // a blocker search + PCF per screen pixel of ground: the ground receives nothing else, and a
      // soft shadow needs far fewer texels than the screen has ground pixels.
      const int gs = std::max(64, I.shadow_size / kGroundShadowDivisor);
      I.ensureGroundShadow(gs);
      glBindFramebuffer(GL_FRAMEBUFFER, I.ground_shadow_fbo);
      glViewport(0, 0, gs, gs);
      I.bindShadowTextures(false);  // the ground texture is the target here
      // Only the texels near a caster are shaded: a texel whose taps find no blocker is fully lit
      // (1), as the cleared texture is. The box holds the casters seen along the light, grown by
      // the widest reach of the taps (the blocker search's kMaxPenumbraMetres, at least 2 texels;
      // draft's 8 texels at most), a texel of bilinear footprint, the normal offset (2.25
      // texels) and two ground texels: the texture is the same as with every texel shaded.
      glClearColor(1.0f, 0.0f, 0.0f, 1.0f);
      glDepthMask(GL_TRUE);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      const double ground_texel = lf.texel_world * double(I.shadow_size) / double(gs);
      int* box = I.ground_shadow_box;
      I.ground_shadow_boxed =
          I.casterTexelBox(lf.view_proj, kMaxPenumbraMetres + 12.0 * lf.texel_world + 2.0 * ground_texel, gs, box);
      if (I.ground_shadow_boxed) {
        const Eigen::Matrix4f lvp = lf.view_proj.cast<float>();
        for (GLuint p : {I.prog_ground_shadow_class, I.prog_ground_shadow}) {
          I.setCommonUniforms(p, lvp, lvp, float(1.5 * lf.texel_world), true);
          setMat4(p, "u_invLightViewProj", lf.view_proj.inverse().cast<float>());
          glUniform1f(loc(p, "u_groundZ"), float(I.params.ground_height));
          glUniform2f(loc(p, "u_groundShadowSize"), float(gs), float(gs));
        }
        glEnable(GL_SCISSOR_TEST);
        glScissor(box[0], box[1], box[2] - box[0], box[3] - box[1]);
        // The blocker search writes the fully lit and umbra texels, the filter runs on the
        // others (draft has no search: one pass).
        drawFullscreenTwoPass(I.empty_vao, draft ? 0 : I.prog_ground_shadow_class, I.prog_ground_shadow);
        glDisable(GL_SCISSOR_TEST);
      }
      glDepthMask(GL_TRUE);
    }
    I.endPass(Impl::kShadowPass, stats_);
  }

  // --- Main pass into the MSAA target. ---
  const Camera& cam = I.camera;
  const double D = std::max((cam.target - cam.eye).norm(), 1e-3);
  // Ground fade measured from the point looked at: fully visible nearby, gone into the haze far.
  const double fade_start = 2.0 * D + 1.0, fade_end = 6.0 * D + 3.0;
  const double ground_half = fade_end * 1.05;
  double znear = cam.znear, zfar = cam.zfar;
  if (znear <= 0.0) {
    double nearest = D;
    if (!I.draw_bounds.isEmpty()) nearest = std::sqrt(I.draw_bounds.squaredExteriorDistance(cam.eye));
    if (I.params.ground) nearest = std::min(nearest, std::max(cam.eye.z() - I.params.ground_height, 0.0));
    znear = std::clamp(0.5 * nearest, 0.002 * D + 1e-4, 0.05 * D + 0.01);
  }
  if (zfar <= 0.0) {
    zfar = (cam.eye - cam.target).norm() + ground_half * 1.5 + 1.0;
    if (!I.draw_bounds.isEmpty())
      for (int i = 0; i < 8; ++i)
        zfar = std::max(zfar, 1.1 * (I.draw_bounds.corner(Eigen::AlignedBox3d::CornerType(i)) - cam.eye).norm());
  }
  const Eigen::Matrix4f view_proj = (cam.projection(double(w) / double(h), znear, zfar) * cam.view()).cast<float>();
  const Eigen::Matrix4f light_vp = lf.view_proj.cast<float>();
  const float normal_offset = float(1.5 * lf.texel_world);

  I.beginPass(Impl::kMainPass);
  stats_.draw_calls = 0;
  const auto setGroundUniforms = [&](GLuint p) {
    I.setCommonUniforms(p, view_proj, light_vp, normal_offset, shadows_on);
    glUniform3f(loc(p, "u_quadCenter"), float(cam.target.x()), float(cam.target.y()), float(I.params.ground_height));
    glUniform1f(loc(p, "u_quadHalf"), float(ground_half));
    glUniform1f(loc(p, "u_quadInner"), 0.0f);
    glUniform1i(loc(p, "u_transparent"), I.params.transparent ? 1 : 0);
    setVec3(p, "u_groundAlbedo", srgbToLinear(I.params.ground_color.cast<float>()));
    glUniform1f(loc(p, "u_gridSpacing"), float(std::max(I.params.grid_spacing, 0.0)));
    glUniform3f(loc(p, "u_fadeCenter"), float(cam.target.x()), float(cam.target.y()), 0.0f);
    glUniform2f(loc(p, "u_fade"), float(fade_start), float(fade_end));
    glUniform1i(loc(p, "u_groundShadow"), 2);
  };
  // The ground square into the bound target of vw x vh pixels, in parts, each with the least its
  // pixels need (the colours are the same): the square inside the circle where the fade starts,
  // without the fade (GROUND_NEAR), and without the shadow lookup outside the pixel rectangle of
  // the shadow texture's shaded texels (GROUND_LIT); then the ring around it to the edge, with
  // both. Most ground pixels are in the square, and the shadows in a small part of it. Leaves the
  // empty VAO bound.
  const auto drawGroundParts = [&](int vw, int vh) {
    for (GLuint p : {I.prog_ground, I.prog_ground_near, I.prog_ground_near_lit}) {
      setGroundUniforms(p);
      glUniform2f(loc(p, "u_viewport"), float(vw), float(vh));
    }
    glBindVertexArray(I.empty_vao);
    const float inner = float(fade_start / std::sqrt(2.0) * 0.999);
    Impl::PixelRect sr{};
    bool whole = false;
    const bool boxed = shadows_on && I.groundShadowRect(view_proj, vw, vh, sr, whole);
    for (GLuint p : {I.prog_ground_near, I.prog_ground_near_lit}) {
      glUseProgram(p);
      glUniform1f(loc(p, "u_quadHalf"), inner);
    }
    if (!boxed || whole) {
      glUseProgram(boxed ? I.prog_ground_near : I.prog_ground_near_lit);
      glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    } else {
      glEnable(GL_SCISSOR_TEST);
      glUseProgram(I.prog_ground_near);
      glScissor(sr.x0, sr.y0, sr.x1 - sr.x0, sr.y1 - sr.y0);
      glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
      glUseProgram(I.prog_ground_near_lit);
      const Impl::PixelRect around[4] = {
          {0, 0, vw, sr.y0}, {0, sr.y1, vw, vh}, {0, sr.y0, sr.x0, sr.y1}, {sr.x1, sr.y0, vw, sr.y1}};
      for (const Impl::PixelRect& a : around) {
        if (a.area() <= 0) continue;
        glScissor(a.x0, a.y0, a.x1 - a.x0, a.y1 - a.y0);
        glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
      }
      glDisable(GL_SCISSOR_TEST);
    }
    glUseProgram(I.prog_ground);
    glUniform1f(loc(I.prog_ground, "u_quadInner"), inner);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 10);
  };
  // Single-sample frames: the ground is shaded at half resolution (a quarter of the pixels) and
  // upsampled bilinearly after the objects. Everything on it is smooth at the pixel scale: the
  // shadow (a soft texture), the lighting, the fade, the background it fades into; the checker is
  // box-filtered over the half-resolution pixel, so its edges stay anti-aliased, a pixel softer.
  // It is most of a final frame's per-pixel shading, and llvmpipe pays for every pixel it shades.
  // The upsampling is also the frame's background: one full-screen copy before the objects, into
  // a target without a depth buffer, instead of the ground square (with its depth test and
  // writes) and the background after them (38 % of the ground's and background's time at
  // 1920x1080). What the ground hid, the object parts on its far side, is clipped at its plane
  // instead (gl_ClipDistance in the objects' vertex shaders).
  const bool half_ground = I.params.ground && samples == 1 && I.ground_lo_fbo != 0;
  // Above the horizon there is no ground, only the background: those rows get the background's
  // own full-screen pass (as a frame without a ground does) instead of the bilinear tap of a
  // half-resolution copy of it, which costs llvmpipe half as much again per pixel; and the
  // half-resolution target needs no background there. sky_row: the first pixel row (from the
  // bottom) left to the background, 2 rows above the horizon's (the bilinear footprint: no tap
  // below it reaches a texel with ground); h: no split (transparent, the eye below the ground, a
  // rolled, upside-down or straight-down view, the horizon out of the frame).
  int sky_row = h;
  if (half_ground && !I.params.transparent && cam.eye.z() > I.params.ground_height &&
      cam.up.normalized().z() > 1.0 - 1e-9) {  // upright: neither rolled nor upside down
    Eigen::Vector3d f = cam.target - cam.eye;
    f.z() = 0.0;
    if (f.norm() > 1e-9) {
      // Every horizontal direction projects onto one row when the camera does not roll.
      const Eigen::Vector4d c = view_proj.cast<double>() * Eigen::Vector4d(f.x(), f.y(), 0.0, 0.0);
      if (c.w() > 1e-9) {
        const double row = (c.y() / c.w() * 0.5 + 0.5) * h;
        if (row > -4.0 && row < h - 4.0) sky_row = std::clamp(int(std::ceil(row)) + 2, 0, h);
      }
    }
  }
  if (half_ground) {
    // 1) The ground, then the background around it, in a half-size texture with a depth buffer of
    // its own (no object in it): the texels around the ground's edge hold the background it fades
    // into (or alpha 0 when transparent), so the upsampled edge blends into what is drawn beside
    // it. First, before the objects: llvmpipe finishes a framebuffer's drawing at every switch,
    // and this order has one switch fewer.
    I.bindShadowTextures(true);
    glBindFramebuffer(GL_FRAMEBUFFER, I.ground_lo_fbo);
    glViewport(0, 0, I.ground_lo_w, I.ground_lo_h);
    glClearColor(0, 0, 0, 0);
    glEnable(GL_DEPTH_TEST);  // (without a shadow pass before it, the state is what the last frame left)
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    drawGroundParts(I.ground_lo_w, I.ground_lo_h);
    if (!I.params.transparent) {
      I.setCommonUniforms(I.prog_bg, view_proj, light_vp, normal_offset, shadows_on);
      glUniform2f(loc(I.prog_bg, "u_viewport"), float(I.ground_lo_w), float(I.ground_lo_h));
      glDepthFunc(GL_LEQUAL);  // the far plane, where the depth is still the cleared 1
      glDepthMask(GL_FALSE);
      // Only the rows the upsampling below sky_row reads (its pixel row y taps rows y / 2 and
      // y / 2 + 1 at most).
      const int lo_rows = std::min(I.ground_lo_h, sky_row / 2 + 2);
      glEnable(GL_SCISSOR_TEST);
      glScissor(0, 0, I.ground_lo_w, lo_rows);
      glDrawArrays(GL_TRIANGLES, 0, 3);
      glDisable(GL_SCISSOR_TEST);
      glDepthMask(GL_TRUE);
      glDepthFunc(GL_LESS);
    }
    glBindVertexArray(0);
    ++stats_.draw_calls;
  }
  glViewport(0, 0, w, h);
  if (half_ground) {
    // 2) A bilinear tap of it per pixel, over the whole frame: the objects are drawn over it.
    glBindFramebuffer(GL_FRAMEBUFFER, I.ground_up_fbo);
    glDisable(GL_DEPTH_TEST);
    const GLuint u = I.prog_ground_up;
    glUseProgram(u);
    glActiveTexture(GL_TEXTURE7);
    glBindTexture(GL_TEXTURE_2D, I.ground_lo_tex);
    glActiveTexture(GL_TEXTURE0);
    glUniform1i(loc(u, "u_groundLo"), 7);
    glBindVertexArray(I.empty_vao);
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, 0, w, sky_row);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    if (sky_row < h) {
      // Its other uniforms are this frame's already: the half-resolution background above set
      // them (a split needs an opaque frame, which draws it).
      glUseProgram(I.prog_bg);
      glUniform2f(loc(I.prog_bg, "u_viewport"), float(w), float(h));
      glScissor(0, sky_row, w, h - sky_row);
      glDrawArrays(GL_TRIANGLES, 0, 3);
      ++stats_.draw_calls;
    }
    glDisable(GL_SCISSOR_TEST);
    glBindVertexArray(0);
    glActiveTexture(GL_TEXTURE7);
    glBindTexture(GL_TEXTURE_2D, 0);  // a render target again next frame
    glActiveTexture(GL_TEXTURE0);
    ++stats_.draw_calls;
  }
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  const bool has_objects = !I.mesh_draws.empty() || !I.hulls.empty() || !I.hair_draws.empty();
  // Deferred shading on a single-sample target: llvmpipe shades whole blocks of pixels, so on a
  // mesh of small triangles a shadow search per fragment runs several times per covered pixel
  // (and again for every hidden layer drawn first). Instead: 1) the objects, their lit shaders
  // writing the visible surface (position, normal) and the two parts of its radiance into three
  // targets, with the main depth buffer; 2) the shadow and the finished colour once per pixel of
  // that surface. The objects are rasterized once, as without shadows.
  const bool deferred = shadows_on && has_objects && samples == 1 && I.surf_fbo != 0;
  const GLuint mesh_prog = deferred ? I.prog_mesh_split : I.prog_mesh;
  const GLuint mesh_mat_prog = deferred ? I.prog_mesh_mat_split : I.prog_mesh_mat;
  const GLuint hull_prog = deferred ? I.prog_hull_split : I.prog_hull;
  const GLuint hair_prog = deferred ? I.prog_hair_split : I.prog_hair;
  glBindFramebuffer(GL_FRAMEBUFFER, deferred ? I.surf_fbo : I.msaa_fbo);
  glClearColor(0, 0, 0, I.params.transparent ? 0 : 1);
  // The colour needs no clear unless the background is left out (transparent): the objects, then
  // the ground and the background where the depth is still the cleared 1, write every pixel (1.7
  // ms of llvmpipe's time at 1920x1080). Deferred: the surface targets are read only where an
  // object is, and the colour target is another one. Over the half-resolution ground, its
  // upsampling has written every pixel already, transparent or not.
  const bool clear_color = I.params.transparent && !half_ground;
  glClear(!deferred && clear_color ? GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT : GL_DEPTH_BUFFER_BIT);
  I.bindShadowTextures(true);
  // Over the half-resolution ground: clip away what is on the ground's far side from the eye (the
  // ground square is not in the depth buffer to hide it). Otherwise the plane is 0 (nothing
  // clipped): llvmpipe clips by gl_ClipDistance even with GL_CLIP_DISTANCE0 disabled
  // (Renderer.TheGroundHidesWhatIsBelowIt, with MSAA).
  const float clip_side = !half_ground ? 0.0f : cam.eye.z() >= I.params.ground_height ? 1.0f : -1.0f;
  for (GLuint p : {mesh_prog, mesh_mat_prog, hull_prog, hair_prog}) {
    I.setCommonUniforms(p, view_proj, light_vp, normal_offset, shadows_on);
    glUniform4f(loc(p, "u_clipPlane"), 0.0f, 0.0f, clip_side, -clip_side * float(I.params.ground_height));
  }
  if (half_ground) glEnable(GL_CLIP_DISTANCE0);
  I.drawGeometry(mesh_prog, hull_prog, view_proj, false);
  I.drawHairs(view_proj, false, ld, hair_prog);
  glDisable(GL_CLIP_DISTANCE0);
  stats_.draw_calls += int(I.hair_draws.size());
  for (const HairDraw& d : I.hair_draws) stats_.triangles += d.count / 3;
  stats_.draw_calls += int(I.mesh_draws.size()) + (I.hulls.empty() ? 0 : 1);
  for (const MeshDraw& d : I.mesh_draws) stats_.triangles += size_t(I.meshes[size_t(d.mesh)].index_count / 3);
  stats_.triangles += I.hulls.size() * I.hull_triangles;
  if (deferred) {
    glBindFramebuffer(GL_FRAMEBUFFER, I.msaa_fbo);
    if (clear_color) glClear(GL_COLOR_BUFFER_BIT);  // as above
    const GLuint targets[] = {I.surf_tex, I.key_tex, I.rest_tex};
    for (int i = 0; i < 3; ++i) {
      glActiveTexture(GLenum(GL_TEXTURE4 + i));
      glBindTexture(GL_TEXTURE_2D, targets[i]);
    }
    glActiveTexture(GL_TEXTURE0);
    for (GLuint p : {I.prog_deferred_class, I.prog_deferred}) {
      I.setCommonUniforms(p, view_proj, light_vp, normal_offset, shadows_on);
      glUniform1i(loc(p, "u_surface"), 4);
      glUniform1i(loc(p, "u_key"), 5);
      glUniform1i(loc(p, "u_rest"), 6);
    }
    // Two passes, each a full-screen triangle just short of the far plane (glDepthRange) with
    // depth test GREATER: it passes where an object is. The first finishes the pixels whose
    // shadow needs no filter (no key light, or nothing above the surface: nothingAbove()) and
    // moves their depth to the triangle's, discarding the others; the second, the whole
    // shadowFactor(), then runs only where an object's depth is left: llvmpipe tests depth
    // before the shader (a discarding shader keeps the early test when it writes no stencil), so
    // the filter costs nothing where it is not needed. Just short of the far plane, so that the
    // background drawn after the objects at the far plane (without a ground) leaves them alone.
    glDepthRange(0.0, 1.0 - std::ldexp(1.0, -19));
    glDepthFunc(GL_GREATER);
    glBindVertexArray(I.empty_vao);
    const bool boxed = I.screenRects(view_proj, w, h, I.rects);
    if (boxed) glEnable(GL_SCISSOR_TEST);
    for (GLuint p : {I.prog_deferred_class, I.prog_deferred}) {
      glUseProgram(p);
      glDepthMask(p == I.prog_deferred_class ? GL_TRUE : GL_FALSE);
      if (boxed) {
        for (const Impl::PixelRect& r : I.rects) {
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
    stats_.draw_calls += 2;
  }
  glDepthFunc(GL_LESS);

  glBindVertexArray(I.empty_vao);
  if (!half_ground) {
    // The ground after the objects: the early depth test skips the pixels they cover, and its
    // nearer fragments still hide whatever is below it. It writes its depth, so that the
    // background, last, fills only the pixels nothing was drawn on (none when transparent: alpha
    // 0 there).
    if (I.params.ground) {
      drawGroundParts(w, h);
      ++stats_.draw_calls;
    }
    if (!I.params.transparent) {
      glDepthFunc(GL_LEQUAL);  // the far plane, where the depth is still the cleared 1
      glDepthMask(GL_FALSE);
      I.setCommonUniforms(I.prog_bg, view_proj, light_vp, normal_offset, shadows_on);
      glDrawArrays(GL_TRIANGLES, 0, 3);
      glDepthMask(GL_TRUE);
      glDepthFunc(GL_LESS);
      ++stats_.draw_calls;
    }
  }
  glBindVertexArray(0);

  if (!I.lines.empty()) {
    // Debug lines (the drag line, render.colliders) over the picture: no depth test.
    glDisable(GL_DEPTH_TEST);
    glUseProgram(I.prog_lines);
    setMat4(I.prog_lines, "u_viewProj", view_proj);
    glBindVertexArray(I.lines_vao);
    glBindBuffer(GL_ARRAY_BUFFER, I.lines_vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(I.lines.size() * sizeof(LineVertex)), I.lines.data(), GL_STREAM_DRAW);
    glDrawArrays(GL_LINES, 0, GLsizei(I.lines.size()));
    glEnable(GL_DEPTH_TEST);
    ++stats_.draw_calls;
  }
  glBindVertexArray(0);
  I.endPass(Impl::kMainPass, stats_);

  // --- Anti-aliasing into the output target: MSAA resolve, or the post-process filter. ---
  if (msaa || post) {
    I.beginPass(Impl::kResolvePass);
    if (msaa) {
      glBindFramebuffer(GL_READ_FRAMEBUFFER, I.msaa_fbo);
      glBindFramebuffer(GL_DRAW_FRAMEBUFFER, I.resolve_fbo);
      glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    } else {
      // The filter runs only over the screen rectangles of what was drawn (objects, hair,
      // lines), grown by its reach; the background and the ground around them have no edges to
      // smooth (the checker is box-filtered, the shadows soft) and are copied as they are.
      // Then the frame stays where it is and is filtered in place there, from a copy of the
      // rectangles and of what the filter's taps reach around them (5 px: 4 along an edge, and a
      // texel of bilinear footprint), instead of a copy of the whole frame.
      const bool boxed = I.screenRects(view_proj, w, h, I.rects);
      GLuint source = I.main_color_tex;
      I.output_fbo = I.resolve_fbo;
      if (boxed) {
        glBindFramebuffer(GL_READ_FRAMEBUFFER, I.msaa_fbo);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, I.post_src_fbo);
        constexpr int kReach = 6;
        for (const Impl::PixelRect& r : I.rects) {
          const int x0 = std::max(r.x0 - kReach, 0), y0 = std::max(r.y0 - kReach, 0);
          const int x1 = std::min(r.x1 + kReach, w), y1 = std::min(r.y1 + kReach, h);
          glBlitFramebuffer(x0, y0, x1, y1, x0, y0, x1, y1, GL_COLOR_BUFFER_BIT, GL_NEAREST);
        }
        source = I.post_src_tex;
        I.output_fbo = I.msaa_fbo;  // its depth buffer is done with: the filter marks edges in it
        glEnable(GL_SCISSOR_TEST);
      }
      glBindFramebuffer(GL_FRAMEBUFFER, I.output_fbo);
      glActiveTexture(GL_TEXTURE3);
      glBindTexture(GL_TEXTURE_2D, source);
      glActiveTexture(GL_TEXTURE0);
      for (GLuint p : {I.prog_post_class, I.prog_post}) {
        glUseProgram(p);
        glUniform1i(loc(p, "u_frame"), 3);
        glUniform2f(loc(p, "u_texel"), 1.0f / float(w), 1.0f / float(h));
      }
      // The first pass copies the pixels without an edge, the filter runs on the others (where
      // rectangles overlap, the second one's passes redo the same pixels with the same result).
      if (boxed) {
        for (const Impl::PixelRect& r : I.rects) {
          glScissor(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
          drawFullscreenTwoPass(I.empty_vao, I.prog_post_class, I.prog_post);
        }
      } else {
        drawFullscreenTwoPass(I.empty_vao, I.prog_post_class, I.prog_post);
      }
      glActiveTexture(GL_TEXTURE3);
      glBindTexture(GL_TEXTURE_2D, 0);  // the main pass renders into it next frame
      glActiveTexture(GL_TEXTURE0);
      glEnable(GL_DEPTH_TEST);
      glDisable(GL_SCISSOR_TEST);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    I.endPass(Impl::kResolvePass, stats_);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!I.software_gl) I.query_frame ^= 1;
  I.in_frame = false;
  stats_.submit_ms = msSince(t0);
}

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

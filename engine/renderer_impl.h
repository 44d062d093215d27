// The renderer's inside, shared by the files that implement engine/renderer.h (not part of the
// engine's interface): the GL objects and the frame's draw list (Renderer::Impl), and FramePlan,
// everything endFrame decides once before it draws.
//
//   renderer.cpp        the public class: init, the draw list, the endFrame driver, read-back
//   frame_plan.cpp      FramePlan: sizes, the shadow map and the light's frustum, the matrices,
//                       which passes run; the screen and texel rectangles the passes are cut to
//   render_passes.cpp   one function per pass, and the drawing they share
//   render_targets.cpp  the framebuffers and their textures, (re)allocated when a size changes
//   mesh_upload.cpp     meshes into vertex arrays (Renderer::upload, release)
#pragma once

#include <glad/gl.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "engine/color.h"
#include "engine/renderer.h"

namespace ponyhop {

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  GLsizei index_count = 0;
  Eigen::AlignedBox3d bbox;
  // With the file's materials (MeshData::colors): drawn by prog_mesh_mat, part by part.
  bool materials = false;
  // With a hair region (MeshData::hair, in the colour's alpha): drawn by prog_mesh_hair instead.
  // Without the file's own colours its triangles are sorted by what their corners are: the first
  // skin_count indices all skin (drawn by prog_mesh, as a mesh without hair), then `parts` (the
  // hairline: both, prog_mesh_hair), then hair_only (all hair, prog_hair_only), so each pixel pays
  // only for the shading it shows.
  bool hair = false;
  GLsizei skin_count = 0;
  MeshPart hair_only;
  // closedOrientation(): +1/-1 closed (back faces culled in both passes), 0 open (both sides drawn).
  int closed = 0;
  // Closed, without materials, and every face's plane has all its vertices on one side: it never
  // shadows its own lit faces (deferredRects).
  bool convex = false;
  std::vector<MeshPart> parts;
  std::vector<GLuint> textures;
  // Simplified copies of a large mesh for the shadow pass alone (shadowLevels, mesh_upload.cpp),
  // finest first, their indices after the mesh's own in the EBO: each within `error` (the mesh's
  // units) of its surface. The main pass always draws the whole mesh.
  struct ShadowLevel {
    float error = 0.0f;
    uint32_t first = 0, count = 0;
  };
  std::vector<ShadowLevel> shadow_levels;
};

// Simplified copies of a large mesh for the shadow pass (mesh_upload.cpp): each within its
// error of the mesh, finest first; their indices, into the mesh's vertices, appended to `indices`.
// None for a mesh under 8192 triangles.
std::vector<GpuMesh::ShadowLevel> shadowLevels(const MeshData& m, std::vector<uint32_t>& indices);
// The index range (first index, count) the shadow pass draws mesh `g` with under `model`, in a
// map of `texel_world` m texels (render_passes.cpp): the coarsest level within a texel, else the
// whole mesh.
std::pair<size_t, GLsizei> shadowRange(const GpuMesh& g, const Eigen::Matrix4f& model, double texel_world);

struct MeshDraw {
  int mesh;
  int part = -1;  // its index in Renderer::Impl::part_bounds
  Eigen::Matrix4f model;
  Eigen::Matrix3f normal;
  Material material;
  ScalpHair hair;
  bool still = false;  // Renderer::drawMesh's `still`
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

// What endFrame decides before it draws (Renderer::Impl::planFrame), from the draw list, the
// camera, the light and the render parameters; the passes only read it.
struct FramePlan {
  // The output: size, quality, anti-aliasing.
  int w = 1, h = 1;
  bool draft = false;  // RenderQuality::Draft
  bool msaa = false;   // a multisampled target, resolved by a blit
  bool post = false;   // a single-sample target, then the post-process filter
  int samples = 1;     // the main target's samples (1: single-sample)
  // The key light's shadow. shadow_size, softness_texels and frustum only when shadows_on.
  Eigen::Vector3d light_dir = Eigen::Vector3d(0, 0, -1);  // unit, from the light
  Eigen::AlignedBox3d casters;
  bool shadows_on = false;
  int shadow_size = 0;           // the shadow map's side this frame (texels)
  double softness_texels = 0.0;  // Impl::softness_texels
  LightFrustum frustum;          // identity when !shadows_on
  // The view: the ground's fade (m from the point looked at) and the matrices.
  double fade_start = 0.0, fade_end = 0.0, ground_half = 0.0;
  Eigen::Matrix4f view_proj = Eigen::Matrix4f::Identity();
  Eigen::Matrix4f light_vp = Eigen::Matrix4f::Identity();
  float normal_offset = 0.0f;  // the shadow lookup's offset along the normal, m
  // Which passes run, and how.
  bool half_ground = false;  // the ground at half resolution, upsampled before the objects
  int sky_row = 1;           // the first pixel row (from the bottom) left to the background's pass
  // With half_ground: the ground drawn at full resolution as a grid lit at its corners instead
  // (gridGroundPass), below grid_top (the first pixel row left to the background's pass).
  bool grid_ground = false;
  int grid_top = 0;
  bool deferred = false;     // the objects' shadows in a pass of their own (deferredLightPass)
  bool clear_color = false;  // the colour target needs a clear (nothing else writes every pixel)
  float clip_side = 0.0f;    // the objects' clip plane at the ground: +1 / -1 the eye's side, 0 none
};

struct Renderer::Impl {
  // Programs.
  GLuint prog_mesh = 0, prog_hull = 0, prog_ground = 0, prog_ground_shadow = 0, prog_lines = 0;
  GLuint prog_mesh_depth = 0, prog_hull_depth = 0, prog_post = 0, prog_bg = 0;
  GLuint prog_hair = 0, prog_hair_depth = 0;
  GLuint prog_mesh_mat = 0;
  GLuint prog_mesh_hair = 0, prog_mesh_hair_split = 0;  // prog_mesh_mat with the hair region (SCALP_HAIR)
  GLuint prog_hair_only = 0, prog_hair_only_split = 0;  // the same, triangles all hair (HAIR_ONLY)
  std::vector<GLuint> programs;                         // every program above, for the destructor
  // Deferred shading (single-sample targets with shadows): the lit programs writing the visible
  // surface and the two parts of its radiance (SPLIT_LIGHT), and the pass that shadows and
  // finishes each visible pixel once.
  GLuint prog_mesh_split = 0, prog_mesh_mat_split = 0, prog_hull_split = 0, prog_hair_split = 0;
  GLuint prog_deferred = 0, prog_deferred_class = 0;
  // The convex casters' split programs that also write the finished, fully lit colour
  // (kSplitLitDefine), for the frames whose deferred shading runs only where another caster can
  // shadow a pixel (deferredRects).
  GLuint prog_mesh_lit = 0, prog_hull_lit = 0;
  GLuint prog_ground_up = 0;            // the half-resolution ground, upsampled (kGroundUpFS)
  GLuint prog_grid = 0;                 // the grid ground (kGridVS, kGridFS)
  GLuint prog_grid_shadow = 0;          // ... per pixel where its shadow may be (kGroundFS, GRID_GROUND)
  GLuint prog_ground_near = 0;          // kGroundFS where nothing fades (GROUND_NEAR)
  GLuint prog_ground_near_lit = 0;      // ... and nothing is shadowed (GROUND_LIT)
  GLuint prog_ground_lit = 0;           // kGroundFS where nothing is shadowed (the ring)
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
  // The grid ground's cells (drawGridGround): indices of the corners (cols + 1 a row, numbered
  // from the bottom left; kGridVS computes each from its number), 6 a cell, row after row.
  GLuint grid_vao = 0, grid_ebo = 0;
  int grid_cols = 0, grid_rows = 0;
  GLuint lines_vao = 0, lines_vbo = 0;
  GLuint hair_vao = 0, hair_vbo = 0, hair_ebo = 0;
  std::vector<GpuMesh> meshes;  // index = MeshHandle::id; vao == 0: released
  int box_mesh = -1;
  // Targets.
  // Main pass target: MSAA renderbuffers (samples > 1, antialias = msaa) or a single-sample colour
  // texture (read by the post-process filter, or directly without anti-aliasing).
  GLuint msaa_fbo = 0, msaa_color = 0, msaa_depth = 0, main_color_tex = 0;
  GLuint resolve_fbo = 0, resolve_color = 0;
  GLuint resolve_depth = 0;  // unused since the post filter works in place (session 28); kept with resolve_fbo
  GLuint output_fbo = 0;     // where the finished frame is: resolve_fbo (MSAA); msaa_fbo without AA or post-filtered
  // The post filter over rectangles: a copy of them (and around them, as far as its taps reach)
  // that it reads while it writes the main target in place (antiAliasPass).
  GLuint post_src_fbo = 0, post_src_tex = 0;
  bool target_post = false;
  // With a single-sample target: position + normal of the visible surface, and the key light's
  // part of its radiance before the shadow and the rest (kDeferredFS), sharing the main depth
  // buffer.
  GLuint surf_fbo = 0, surf_tex = 0, key_tex = 0, rest_tex = 0;
  // With a single-sample target: the ground (over the background) at half resolution.
  GLuint ground_lo_fbo = 0, ground_lo_tex = 0, ground_lo_depth = 0;
  GLuint ground_up_fbo = 0;                         // main_color_tex without a depth buffer
  GLuint ground_full_fbo = 0, ground_full_tex = 0;  // the upsampled ground kept (groundKey)
  int ground_lo_w = 0, ground_lo_h = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;
  GLuint raw_depth_sampler = 0;                         // reads shadow_tex without comparison (blocker search)
  GLuint ground_shadow_fbo = 0, ground_shadow_tex = 0;  // R8, shadowFactor on the ground plane
  GLuint ground_shadow_depth = 0;                       // marks the texels that need the filter
  int ground_shadow_size = 0;
  // This frame's texels of the ground's shadow texture that are not 1 (lit) lie in the boxes
  // ground_shadow_boxes (below); none when !ground_shadow_boxed.
  bool ground_shadow_boxed = false;
  // The last frame with shadows' light frustum and filter radius (setCommonUniforms reads them).
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
  Eigen::AlignedBox3d still_bounds;              // the still mesh draws' (Renderer::drawMesh)
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
  std::chrono::steady_clock::time_point pass_t0;
  void beginPass(Pass p);
  void endPass(Pass p, RenderStats& st);
  void collectGpuTimes(RenderStats& st);

  // Construction (renderer.cpp).
  bool buildPrograms(std::string* err);
  void makeStaticGeometry();

  // Planning (frame_plan.cpp).
  FramePlan planFrame() const;
  void planShadows(FramePlan& f) const;
  void planView(FramePlan& f) const;
  void planPasses(FramePlan& f) const;
  struct PixelRect {
    int x0, y0, x1, y1;  // [x0, x1) x [y0, y1)
    int64_t area() const { return int64_t(x1 - x0) * (y1 - y0); }
    bool empty() const { return x1 <= x0 || y1 <= y0; }
    PixelRect operator&(const PixelRect& o) const {  // the intersection
      return {std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
    }
    PixelRect operator|(const PixelRect& o) const {  // the box around both (an empty one counts as none)
      if (empty()) return o;
      if (o.empty()) return *this;
      return {std::min(x0, o.x0), std::min(y0, o.y0), std::max(x1, o.x1), std::max(y1, o.y1)};
    }
  };
  // skip: parts (by part_bounds index) left out; none when there are too many parts to box alone.
  bool screenRects(const Eigen::Matrix4f& view_proj, int w, int h, std::vector<PixelRect>& rects,
                   const std::vector<char>* skip = nullptr) const;
  // Where the post filter classifies and filters (antiAliasPass): triangles in normalized device
  // coordinates (LineVertex, colour unused) covering each draw's screen rectangle, but for a box
  // (drawBox) only bands along the lines where its picture can have an edge; the whole frame when
  // !boxed. Pixels outside them are left as they are.
  // shadow_reach: the farthest a shadow's penumbra reaches past its caster's, in light-space metres.
  void postFilterRegions(const FramePlan& f, bool boxed, double shadow_reach, std::vector<LineVertex>& tris) const;
  std::vector<LineVertex> post_tris;  // scratch of antiAliasPass
  std::vector<PixelRect> rects;       // scratch of the passes (kept: no allocation per frame)
  // The texel boxes of a size x size texture over the light's square that hold everything drawn
  // into the shadow map, seen along the light, each grown by `margin_m` metres: one per caster
  // (a mesh draw, the hulls, the hair). Empty when nothing casts.
  // `moving_only`: the boxes of every caster but the still mesh draws.
  void casterTexelBoxes(const Eigen::Matrix4d& light_vp, double margin_m, int size, std::vector<PixelRect>& out,
                        bool moving_only = false) const;
  // Merges rectangles while the box around a pair adds no more pixels than the two overlap or
  // than `slack`.
  static void mergeRects(std::vector<PixelRect>& rects, int64_t slack);
  // The pixel rectangles (of a w x h viewport) outside which the ground is lit: its shadow texture
  // reads 1 there. One per caster (casterCorners: the ground it shadows, grown by the taps'
  // reach, the part behind the near plane cut off, projected), merged. False: none (nothing shadowed, or all of it
  // behind the eye); `whole` set when they cannot be bounded. groundShadowRect: the box around them.
  bool groundShadowRects(const Eigen::Matrix4f& view_proj, int w, int h, std::vector<PixelRect>& out,
                         bool& whole) const;
  bool groundShadowRect(const Eigen::Matrix4f& view_proj, int w, int h, PixelRect& rect, bool& whole) const;
  // Splits `clip` into disjoint rectangles inside the union of `rects` and outside it (bands of
  // rows, each cut where a rectangle starts or ends; a band's pieces merged with the one below
  // when they line up).
  static void partitionRects(const std::vector<PixelRect>& rects, const PixelRect& clip, std::vector<PixelRect>& inside,
                             std::vector<PixelRect>& outside);
  std::vector<PixelRect> ground_shadow_boxes;  // this frame's casters' texel boxes (casterTexelBoxes)
  // The light's direction (unit) and the taps' reach in light-space metres that those boxes were
  // grown by, for groundShadowRects.
  Eigen::Vector3d ground_shadow_light = Eigen::Vector3d(0, 0, -1);
  double ground_shadow_reach = 0.0;
  void casterCorners(std::vector<std::array<Eigen::Vector3d, 8>>& out) const;

  // Kept between frames (shadowMapPass, groundShadowPass): while the still draws and everything
  // the two textures depend on stay the same (shadowKey(): the frustum, the sizes, the still draws;
  // empty without still draws), shadow_tex keeps their depth and the last frame's moving casters'
  // depth lies in its texels shadow_moving (cleared and drawn anew there), and the ground's shadow
  // texture is shaded again only over its texels near this frame's and the last frame's moving
  // casters (ground_shadow_moving). shadow_tex_key / ground_shadow_key: the key each texture was
  // drawn under (empty: nothing kept). shadow_kept: this frame kept them (RenderStats).
  std::vector<float> shadowKey(const FramePlan& f, int ground_size) const;
  std::vector<float> shadow_tex_key, ground_shadow_key;
  std::vector<PixelRect> shadow_moving, ground_shadow_moving;
  bool shadow_kept = false;

  // The ground kept between frames (halfGroundPass, upsampleGroundPass). Outside the pixel
  // rectangle its shadow texture shades (groundShadowRect), the ground and the background depend
  // only on what groundKey() holds: while that stays the same (a fixed camera and light), a frame
  // draws again only where the last frame's shadow or this one's is. ground_key: the key of what
  // ground_lo_tex holds (empty: nothing kept); ground_lo_shadow: the last frame's shadow rectangle
  // in its pixels (empty: none), ground_lo_whole: it could not be bounded. ground_full_key: the key
  // of ground_full_tex, the upsampled ground and sky at full size (empty: not kept), copied into
  // the main target instead of upsampling the whole frame again.
  std::vector<float> groundKey(const FramePlan& f) const;
  std::vector<float> ground_key, ground_full_key;
  PixelRect ground_lo_shadow{0, 0, 0, 0};
  bool ground_lo_whole = false;
  bool ground_lo_kept = false;            // this frame drew ground_lo_tex again only in ...
  PixelRect ground_lo_dirty{0, 0, 0, 0};  // ... these pixels of it

  // Targets (render_targets.cpp).
  void ensureTargets(int w, int h, int samples, bool post);
  void ensureSingleSampleTargets(int w, int h);  // with ensureTargets(w, h, 1, post)
  void ensureShadowMap(int size);
  void ensureGroundShadow(int size);
  void bindShadowTextures(bool ground_shadow);  // units 0, 1: the shadow map; 2: the ground's

  // The passes, in the order endFrame runs them (render_passes.cpp).
  void uploadFrameData();
  void shadowMapPass(const FramePlan& f);
  void groundShadowPass(const FramePlan& f);
  void halfGroundPass(const FramePlan& f, RenderStats& st);
  void upsampleGroundPass(const FramePlan& f, RenderStats& st);
  using GroundDraw = void (Impl::*)(const FramePlan&, const PixelRect&, RenderStats&);
  void keptGroundPass(const FramePlan& f, bool kept, const PixelRect& dirty, GroundDraw draw, RenderStats& st);
  void gridGroundPass(const FramePlan& f, RenderStats& st);
  void drawGridGround(const FramePlan& f, const PixelRect& clip, RenderStats& st);
  void backgroundRows(const FramePlan& f, const PixelRect& clip, int row, RenderStats& st);
  void objectsPass(const FramePlan& f, RenderStats& st);
  // The pixel rectangles where a pixel of the objects may be shadowed by a caster other than
  // itself (the whole draw of a caster that is not convex; of a convex one, only where another
  // caster's light-space box reaches), into `out`; false when that saves too little of the
  // deferred shading's rectangles to pay for the lit colour the objects pass then writes, or no
  // caster is convex. shadow_marked: this frame's objects pass finished the convex casters'
  // pixels, and the deferred shading runs only over mark_rects.
  bool deferredRects(const FramePlan& f, std::vector<PixelRect>& out) const;
  std::vector<PixelRect> mark_rects;
  bool shadow_marked = false;
  void deferredLightPass(const FramePlan& f, RenderStats& st);
  void groundAndBackgroundPass(const FramePlan& f, RenderStats& st);
  void linesPass(const FramePlan& f, RenderStats& st);
  void antiAliasPass(const FramePlan& f);
  // What the passes share.
  void setCommonUniforms(GLuint prog, const Eigen::Matrix4f& view_proj, const Eigen::Matrix4f& light_vp,
                         float normal_offset, bool shadows_on);
  void setFrameUniforms(GLuint prog, const FramePlan& f) {
    setCommonUniforms(prog, f.view_proj, f.light_vp, f.normal_offset, f.shadows_on);
  }
  // clip: the pixels of the vw x vh viewport to draw (the ground kept outside them).
  void drawGroundParts(const FramePlan& f, int vw, int vh, const PixelRect& clip);
  void upsampleGround(const FramePlan& f, const PixelRect& clip, RenderStats& st);
  // still: depth only, which mesh draws (-1 every one, 0 the moving, 1 the still; the hulls with
  // the moving). mesh_lit_prog: the program for the convex meshes (GpuMesh::convex), 0: mesh_prog
  // for all.
  void drawGeometry(GLuint mesh_prog, GLuint hull_prog, const Eigen::Matrix4f& view_proj, bool depth_only,
                    int still = -1, GLuint mesh_lit_prog = 0);
  // prog: the program for the main pass's camera-facing ribbons (0: prog_hair).
  void drawHairs(const Eigen::Matrix4f& view_proj, bool depth_only, const Eigen::Vector3d& light_dir, GLuint prog = 0);
  void drawMaterialMeshes(GLuint prog, bool hair, bool hair_only);
};

}  // namespace ponyhop

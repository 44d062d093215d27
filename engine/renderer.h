// The renderer: one draw list per frame, drawn with a shadowed key light, a fill light, hemispheric
// ambient and a rim, over a fading checker ground and a gradient background, into its own MSAA
// framebuffer. The same class serves headless output (readPixels) and the window (blitTo).
//
//   auto ctx = HeadlessContext::create(w, h, &err);   // or a GLFW window + loadGL(glfwGetProcAddress)
//   Renderer r;  r.init(&err);
//   MeshHandle head = r.upload(mesh_data);
//   r.beginFrame(camera, light, render_params);
//   r.drawMesh(head, pose, skin);  r.drawTaperedCapsule(a, b, ra, rb, paint);  r.drawHair(tail);  ...
//   r.endFrame();                          // shadow pass + main pass + MSAA resolve
//   r.readPixels(rgba);                    // RGBA8, top row first
//
// Needs a current GL 3.3 core context with GL loaded (loadGL) for every call, including the
// destructor.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/camera.h"
#include "engine/hair.h"
#include "engine/mesh.h"
#include "sim/scene.h"

namespace ponyhop {

// Colours are display (sRGB) values 0..1, as in scene files; lighting happens in linear space.
struct Material {
  Eigen::Vector3f color{0.8f, 0.8f, 0.8f};
  float specular = 0.15f;   // 0..1, strength of the Blinn-Phong highlight
  float shininess = 40.0f;  // Blinn-Phong exponent
  float rim = 0.3f;         // 0..1, strength of the sky-coloured edge light
};

// A head's hair region (MeshData::hair) drawn as hair: the colour (display, as Material's) and the
// strands' shading of its ponytail, combed along the meridians about `axis` (world, unit: from the
// head's centre towards the ponytail's anchor).
struct ScalpHair {
  Eigen::Vector3f color{0.36f, 0.22f, 0.12f};
  HairShading shading;
  Eigen::Vector3d axis{0.0, 0.0, 1.0};
};

struct MeshHandle {
  int id = -1;
  bool valid() const { return id >= 0; }
};

// Where a frame's time goes, per pass. With a software rasterizer (llvmpipe: the CPU is the GPU,
// and it rasterizes each framebuffer's work synchronously when the framebuffer changes or on a
// flush) every pass ends with glFinish and its wall time is taken: the pass's own cost, exactly,
// and the fences cost nothing llvmpipe would not do anyway. With a hardware GPU the passes are
// measured with GL_TIME_ELAPSED queries read one frame late (no stall); timed_on_gpu says which.
struct RenderStats {
  double submit_ms = 0.0;     // wall time of endFrame (all passes, CPU side included)
  double shadow_ms = 0.0;     // shadow map (depth from the key light) + the ground's shadow texture
  double main_ms = 0.0;       // background + ground + objects + lines
  double resolve_ms = 0.0;    // MSAA resolve / post-process anti-aliasing into the output target
  double readback_ms = 0.0;   // readPixels, which waits for the GPU (llvmpipe) to finish
  bool timed_on_gpu = false;  // pass times from GL timer queries (the previous frame's)
  size_t triangles = 0;       // main pass, excluding ground and background
  int draw_calls = 0;         // main pass
  int samples = 0;            // MSAA samples actually used (1: none)
  bool post_aa = false;       // the post-process anti-aliasing filter ran
  bool draft = false;         // RenderQuality::Draft
  int shadow_size = 0;        // the shadow map's side this frame (texels; 0: no shadow pass)
  // The still draws' depth in the shadow map, and the ground's shadow texture away from the
  // moving casters, kept from the last frame (drawMesh's `still`; docs/RENDERING.md, Shadows).
  bool shadow_kept = false;
  // Single-sample with shadows: the objects pass finished the convex casters' pixels that no other
  // caster can shadow, and the deferred shading ran only on the others (the shadow mark).
  bool shadow_marked = false;
};

// The shadow map's sides over several frames (RenderStats::shadow_size), for summaries.
struct ShadowSizeRange {
  int lo = 0, hi = 0;  // texels; 0: no frame had a shadow pass
  void add(const RenderStats& st) {
    if (st.shadow_size <= 0) return;
    lo = lo ? std::min(lo, st.shadow_size) : st.shadow_size;
    hi = std::max(hi, st.shadow_size);
  }
  // "1024" or "512-609"; "" when there was none.
  std::string text() const {
    if (hi == 0) return "";
    return lo == hi ? std::to_string(hi) : std::to_string(lo) + "-" + std::to_string(hi);
  }
};

class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Compiles the shaders and builds the static primitives. False + message on failure.
  bool init(std::string* err);

  // Uploads a mesh once; draw it any number of times per frame with any transform.
  MeshHandle upload(const MeshData& mesh);
  void release(MeshHandle h);

  void beginFrame(const Camera& camera, const LightParams& light, const RenderParams& params);
  // Optional: fit the shadow frustum to these bounds instead of the draw list's (a fixed box
  // keeps shadow texels still while things move; the draw list's bounds are the tightest).
  void setShadowBounds(const Eigen::AlignedBox3d& bounds);
  // `hair`: how a mesh with a hair region draws it (a mesh without one ignores it). `still`: the
  // scene says this draw does not move (static geometry, e.g. terrain): the light's frustum is
  // placed around the still draws, and their depth in the shadow map and their shadow on the
  // ground are kept from frame to frame while the frustum and every still draw stay the same (a
  // draw that changes is found and drawn anew: the flag only makes keeping likely).
  void drawMesh(MeshHandle mesh, const Eigen::Affine3d& model, const Material& m, const ScalpHair& hair = {},
                bool still = false);
  void drawSphere(const Eigen::Vector3d& center, double radius, const Material& m);
  void drawBox(const Eigen::Affine3d& pose, const Eigen::Vector3d& half_extents, const Material& m, bool still = false);
  void drawCapsule(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double radius, const Material& m);
  // Convex hull of the spheres (p0, r0), (p1, r1): smooth rounded ends; consecutive segments that
  // share an end point and radius join without a gap or a crease.
  void drawTaperedCapsule(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double r0, double r1,
                          const Material& m);
  // Strands (ribbons widened in the vertex shader) and a core tube, shaded as hair (Kajiya-Kay
  // highlights along the tangent); they cast and receive shadows. See engine/hair.h.
  void drawHair(const HairMesh& hair);
  void drawLine(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3f& color);
  // Shadow pass, main pass (background, ground, objects, lines), MSAA resolve.
  void endFrame();

  // The last frame as RGBA8 rows, top row first (width() * height() * 4 bytes).
  void readPixels(std::vector<uint8_t>& rgba);
  // Copies the last frame into framebuffer `fbo` (0: the window's), scaled to w x h.
  void blitTo(unsigned fbo, int w, int h) const;

  int width() const { return width_; }
  int height() const { return height_; }
  const RenderStats& stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int width_ = 0, height_ = 0;
  RenderStats stats_;
};

}  // namespace ponyhop

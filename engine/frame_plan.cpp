// FramePlan: what endFrame decides once, before it draws (engine/renderer_impl.h). Then the
// rectangles that passes are cut to: the screen rectangles of the objects, the texel box of the
// casters in the ground's shadow texture, and the pixel rectangle of the ground that it shadows.
//
// Index of this file:
// [SECTION] The light's frustum and the shadow map's size
// [SECTION] The plan
// [SECTION] Where the passes run: screen and texel rectangles

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "engine/renderer_impl.h"

namespace ponyhop {

// ---------------------------------------------------------------------------------------------
// [SECTION] The light's frustum and the shadow map's size

namespace {

// The fewest texels a side resolutionMatchedShadowSize() gives a shadow map.
constexpr int kMinMatchedShadowSize = 512;

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

// The light-space grid, in texels, that the frustum's centre keeps to when there are still
// casters (fitLightFrustum), and its depth range's in parts of the extent.
constexpr double kStillCentreTexels = 32.0;
constexpr double kStillDepthParts = 8.0;

// Fits the light's orthographic box to the casters and to their shadows on the ground: the points
// are the bounds' corners and those corners pushed along the light onto the ground (z = ground_z).
// The square extent
// is rounded up to steps of 2^(1/4) and the centre snapped to whole texels, so that a moving scene
// changes the shadow map's texel grid rarely and only by whole texels (no crawling edges).
// With still casters (`still` not empty: drawn with Renderer::drawMesh's `still`), the box is
// placed so that it holds still while the moving casters stay well inside it, and the shadow map's
// still part can be kept between frames (render_passes.cpp): the same extent and texel lattice,
// but the centre on a coarser grid of the lattice (kStillCentreTexels), the grid point nearest the
// still casters' centre that keeps every caster at least the margin below inside (else the centre
// as without), and the near and far planes snapped outward to a grid of extent / kStillDepthParts
// (a coarser depth step: the range is at most a quarter of the extent longer).
LightFrustum fitLightFrustum(const Eigen::Vector3d& dir, const Eigen::AlignedBox3d& casters, int size,
                             double softness_texels, double ground_z,
                             const Eigen::AlignedBox3d& still = Eigen::AlignedBox3d()) {
  LightFrustum lf;
  const Eigen::Matrix4d V = lookAlong(dir);
  const Eigen::Matrix3d R = V.block<3, 3>(0, 0);
  const auto lightSpace = [&](const Eigen::AlignedBox3d& box) {
    Eigen::AlignedBox3d ls;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d c = box.corner(Eigen::AlignedBox3d::CornerType(i));
      ls.extend(R * c);
      const double above = c.z() - ground_z;
      if (dir.z() < -1e-3 && above > 0.0) ls.extend(R * (c + dir * (above / -dir.z())));
    }
    return ls;
  };
  const Eigen::AlignedBox3d ls = lightSpace(casters);
  double extent = std::max(ls.sizes().x(), ls.sizes().y());
  extent = std::max(extent, 1e-3);
  // Margin for the PCF kernel and the normal offset (a few texels).
  const double margin = extent * (2.0 + softness_texels) / double(size);  // a side
  extent *= 1.0 + (4.0 + 2.0 * softness_texels) / double(size);
  extent = std::pow(2.0, std::ceil(std::log2(extent) * 4.0) / 4.0);
  const double texel = extent / double(size);
  Eigen::Vector2d center = 0.5 * (ls.min().head<2>() + ls.max().head<2>());
  center = (center / texel).array().round().matrix() * texel;
  const double depth_margin = 0.05 * std::max(ls.sizes().z(), extent) + 1e-3;
  double n = -ls.max().z() - depth_margin, f = -ls.min().z() + depth_margin;
  if (!still.isEmpty()) {
    const Eigen::Vector2d anchor = lightSpace(still).center().head<2>();
    const double g = kStillCentreTexels * texel;
    for (int k = 0; k < 2; ++k) {
      // The centres (grid points) that keep [ls.min, ls.max] at least `margin` inside.
      const double lo = std::ceil((ls.max()(k) + margin - 0.5 * extent) / g);
      const double hi = std::floor((ls.min()(k) - margin + 0.5 * extent) / g);
      if (lo <= hi) center(k) = std::clamp(std::round(anchor(k) / g), lo, hi) * g;
    }
    const double gz = extent / kStillDepthParts;
    n = std::floor(n / gz) * gz;
    f = std::ceil(f / gz) * gz;
  }
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

}  // namespace

// ---------------------------------------------------------------------------------------------
// [SECTION] The plan

FramePlan Renderer::Impl::planFrame() const {
  FramePlan f;
  f.w = std::clamp(params.width, 1, 16384);
  f.h = std::clamp(params.height, 1, 16384);
  // Quality: draft drops anti-aliasing and takes a half-size shadow map (512 at the default 1024)
  // with a plain filter.
  f.draft = params.quality == RenderQuality::Draft;
  const bool aa = !f.draft && params.samples > 1;
  f.msaa = aa && params.antialias == AntiAlias::Msaa;
  f.post = aa && !f.msaa;
  f.samples = f.msaa ? std::clamp(params.samples, 1, std::max(max_samples, 1)) : 1;
  planShadows(f);
  planView(f);
  planPasses(f);
  return f;
}

// The casters (every draw, or setShadowBounds), the light's direction, the shadow map's side
// (matched to the frame unless there is hair), the shadow filter's radius and the light's frustum.
void Renderer::Impl::planShadows(FramePlan& f) const {
  f.casters = have_shadow_bounds ? shadow_bounds : draw_bounds;
  Eigen::Vector3d ld = light.direction;
  if (ld.norm() < 1e-9) ld = Eigen::Vector3d(-0.5, 0.6, -1.0);
  f.light_dir = ld.normalized();
  f.shadows_on = !f.casters.isEmpty() && light.intensity > 0.0;
  if (!f.shadows_on) return;
  const int max_size = std::clamp(light.shadow_size, 64, 8192);
  const double extent =
      fitLightFrustum(f.light_dir, f.casters, max_size, light.shadow_softness, params.ground_height).texel_world *
      double(max_size);
  // Not with hair: a strand is thinner than a texel (drawn a texel wide), and its shadow is the
  // share of texels its depth covers, which depends on the texel's size whatever the pixel's
  // (the chain's shadow on the ground at 1920x1080 came out lighter and grainy on a map of 609
  // texels, whose texels were still a tenth of a pixel there).
  const bool match = light.shadow_match && hair_draws.empty();
  const int size = !match ? max_size
                          : resolutionMatchedShadowSize(camera, f.h, f.light_dir, f.casters, params.ground_height,
                                                        extent, kMinMatchedShadowSize, max_size);
  f.shadow_size = f.draft ? std::max(256, size / 2) : size;
  const int unmatched = f.draft ? std::max(256, max_size / 2) : max_size;
  // (at most 8 texels, the widest the margins around the casters allow: only a shadow_size
  // above 4096 matched down to 512 reaches it)
  f.softness_texels =
      std::min(std::clamp(light.shadow_softness, 0.0, 8.0) * double(unmatched) / double(f.shadow_size), 8.0);
  f.frustum = fitLightFrustum(f.light_dir, f.casters, f.shadow_size, f.softness_texels, params.ground_height,
                              have_shadow_bounds ? Eigen::AlignedBox3d() : still_bounds);
}

// The ground's fade, the near and far planes, the camera's and the light's matrices.
void Renderer::Impl::planView(FramePlan& f) const {
  const Camera& cam = camera;
  const double D = std::max((cam.target - cam.eye).norm(), 1e-3);
  // Ground fade measured from the point looked at: fully visible nearby, gone into the haze far.
  f.fade_start = 2.0 * D + 1.0;
  f.fade_end = 6.0 * D + 3.0;
  f.ground_half = f.fade_end * 1.05;
  double znear = cam.znear, zfar = cam.zfar;
  if (znear <= 0.0) {
    double nearest = D;
    if (!draw_bounds.isEmpty()) nearest = std::sqrt(draw_bounds.squaredExteriorDistance(cam.eye));
    if (params.ground) nearest = std::min(nearest, std::max(cam.eye.z() - params.ground_height, 0.0));
    znear = std::clamp(0.5 * nearest, 0.002 * D + 1e-4, 0.05 * D + 0.01);
  }
  if (zfar <= 0.0) {
    zfar = (cam.eye - cam.target).norm() + f.ground_half * 1.5 + 1.0;
    if (!draw_bounds.isEmpty())
      for (int i = 0; i < 8; ++i)
        zfar = std::max(zfar, 1.1 * (draw_bounds.corner(Eigen::AlignedBox3d::CornerType(i)) - cam.eye).norm());
  }
  f.view_proj = (cam.projection(double(f.w) / double(f.h), znear, zfar) * cam.view()).cast<float>();
  f.light_vp = f.frustum.view_proj.cast<float>();
  f.normal_offset = float(1.5 * f.frustum.texel_world);
}

// Which of the main pass's parts run and how: the half-resolution ground and the sky row above
// it, deferred shadows, the colour clear, the objects' clip plane.
void Renderer::Impl::planPasses(FramePlan& f) const {
  const Camera& cam = camera;
  // Single-sample frames: the ground is shaded at half resolution (a quarter of the pixels) and
  // upsampled bilinearly after the objects. Everything on it is smooth at the pixel scale: the
  // shadow (a soft texture), the lighting, the fade, the background it fades into; the checker is
  // box-filtered over the half-resolution pixel, so its edges stay anti-aliased, a pixel softer.
  // It is most of a final frame's per-pixel shading, and llvmpipe pays for every pixel it shades.
  // The upsampling is also the frame's background: one full-screen copy before the objects, into
  // a target without a depth buffer, instead of the ground square (with its depth test and
  // writes) and the background after them (see docs/RENDERING.md, Passes). What the ground hid,
  // the object parts on its far side, is clipped at its plane instead (gl_ClipDistance in the
  // objects' vertex shaders). ensureTargets makes the half-resolution target with every
  // single-sample one.
  f.half_ground = params.ground && f.samples == 1;
  // Above the horizon there is no ground, only the background: those rows get the background's
  // own full-screen pass (as a frame without a ground does) instead of the bilinear tap of a
  // half-resolution copy of it, which costs llvmpipe more per pixel (docs/RENDERING.md, Passes);
  // and the half-resolution target needs no background there. sky_row: the first pixel row (from
  // the bottom) left to the background, 2 rows above the horizon's (the bilinear footprint: no
  // tap below it reaches a texel with ground); h: no split (transparent, the eye below the
  // ground, a rolled, upside-down or straight-down view, the horizon out of the frame).
  // grid_ground: with the sky row, the ground as a grid lit at its corners instead of the
  // half-resolution pass and its upsampling (docs/RENDERING.md, Passes, "The grid ground").
  f.sky_row = f.h;
  if (f.half_ground && !params.transparent && cam.eye.z() > params.ground_height &&
      cam.up.normalized().z() > 1.0 - 1e-9) {  // upright: neither rolled nor upside down
    Eigen::Vector3d fwd = cam.target - cam.eye;
    fwd.z() = 0.0;
    if (fwd.norm() > 1e-9) {
      // Every horizontal direction projects onto one row when the camera does not roll.
      const Eigen::Vector4d c = f.view_proj.cast<double>() * Eigen::Vector4d(fwd.x(), fwd.y(), 0.0, 0.0);
      if (c.w() > 1e-9) {
        const double row = (c.y() / c.w() * 0.5 + 0.5) * f.h;
        if (row > -4.0 && row < f.h - 4.0) f.sky_row = std::clamp(int(std::ceil(row)) + 2, 0, f.h);
        // The grid ground: every ground point seen in a row at or above grid_top is at least R
        // ahead of the eye (a row is a distance ahead when the camera does not roll), so at
        // least fade_end from the point looked at: faded out, the background's colour. Its
        // grid's corners are all on the ground, 2 rows or more below the horizon.
        const Eigen::Vector3d fwd_unit = fwd.normalized();
        Eigen::Vector3d off = cam.eye - cam.target;
        off.z() = 0.0;
        const double R = f.fade_end + off.norm() + 1e-3 * f.fade_end;
        const Eigen::Vector3d q(cam.eye.x() + R * fwd_unit.x(), cam.eye.y() + R * fwd_unit.y(), params.ground_height);
        const Eigen::Vector4d cq = f.view_proj.cast<double>() * q.homogeneous();
        if (cq.w() > 1e-9) {
          const double row_r = (cq.y() / cq.w() * 0.5 + 0.5) * f.h;
          const double top = std::min(std::ceil(row_r), std::floor(row) - 2.0);
          f.grid_ground = true;
          f.grid_top = int(std::clamp(top, 0.0, double(f.h)));
        }
      }
    }
  }
  const bool has_objects = !mesh_draws.empty() || !hulls.empty() || !hair_draws.empty();
  // Deferred shading on a single-sample target: llvmpipe shades whole blocks of pixels, so on a
  // mesh of small triangles a shadow search per fragment runs several times per covered pixel
  // (and again for every hidden layer drawn first). Instead: 1) the objects, their lit shaders
  // writing the visible surface (position, normal) and the two parts of its radiance into three
  // targets, with the main depth buffer; 2) the shadow and the finished colour once per pixel of
  // that surface. The objects are rasterized once, as without shadows. (ensureTargets makes the
  // surface targets with every single-sample target.)
  f.deferred = f.shadows_on && has_objects && f.samples == 1;
  // The colour needs no clear unless the background is left out (transparent): the objects, then
  // the ground and the background where the depth is still the cleared 1, write every pixel (what
  // the clear cost: docs/RENDERING.md, Passes). Deferred: the surface targets are read only where
  // an object is, and the colour target is another one. Over the half-resolution ground, its
  // upsampling has written every pixel already, transparent or not.
  f.clear_color = params.transparent && !f.half_ground;
  // Over the half-resolution ground: clip away what is on the ground's far side from the eye (the
  // ground square is not in the depth buffer to hide it). Otherwise the plane is 0 (nothing
  // clipped): llvmpipe clips by gl_ClipDistance even with GL_CLIP_DISTANCE0 disabled
  // (Renderer.TheGroundHidesWhatIsBelowIt, with MSAA).
  f.clip_side = !f.half_ground ? 0.0f : cam.eye.z() >= params.ground_height ? 1.0f : -1.0f;
}

// ---------------------------------------------------------------------------------------------
// [SECTION] Where the passes run: screen and texel rectangles

// The pixel rectangles that the draw list and the debug lines cover in the main pass, each grown
// by the post filter's reach (its taps go 4 px along an edge): one per draw (its bounding box,
// projected), merged while a merge adds no more pixels than the two overlap or than a few 16x16
// blocks. The full-screen passes that only matter where an object is (the deferred shading, the
// post filter) run scissored to each: llvmpipe pays for every block a triangle covers, even where
// the early depth test then rejects it, and a hopper's body, leg and hair fill a third of their
// common box. False when they cover nearly the whole frame anyway, or a point is behind the eye
// (its projection is not bounded).
bool Renderer::Impl::screenRects(const Eigen::Matrix4f& view_proj, int w, int h, std::vector<PixelRect>& out,
                                 const std::vector<char>* skip) const {
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
    if (b.isEmpty() || (!one && skip && (*skip)[k])) continue;
    for (int i = 0; i < 8; ++i)
      if (!add(b.corner(Eigen::AlignedBox3d::CornerType(i)))) return false;
    emit();
  }
  if (!lines.empty()) {
    for (const LineVertex& v : lines)
      if (!add(Eigen::Vector3d(v.pos[0], v.pos[1], v.pos[2]))) return false;
    emit();
  }
  const auto overlap = [](const PixelRect& a, const PixelRect& b) {
    const int64_t dx = std::min(a.x1, b.x1) - std::max(a.x0, b.x0), dy = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
    return dx > 0 && dy > 0 ? dx * dy : int64_t(0);
  };
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < out.size() && !merged; ++i)
      for (size_t j = i + 1; j < out.size() && !merged; ++j) {
        const PixelRect u = out[i] | out[j];
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

namespace {

// The corners of a box drawn by drawBox (the box mesh's [-1, 1]^3 under `model`): corner i has
// x, y, z at +1 where bits 0, 1, 2 of i are set. Face (axis k, side s) in order around it.
std::array<int, 4> boxFace(int k, int s) {
  const int a1 = 1 << ((k + 1) % 3), a2 = 1 << ((k + 2) % 3), b = s > 0 ? 1 << k : 0;
  return {b, b | a1, b | a1 | a2, b | a2};
}

// Where the quad q (corners in order around it) crosses the plane coordinate[axis] = value: the
// segment between the two points where its edges change side. False when it does not.
bool quadCut(const std::array<Eigen::Vector3d, 4>& q, int axis, double value, Eigen::Vector3d& p0,
             Eigen::Vector3d& p1) {
  int n = 0;
  for (int i = 0; i < 4 && n < 2; ++i) {
    const Eigen::Vector3d &a = q[size_t(i)], &b = q[size_t((i + 1) % 4)];
    const double da = a[axis] - value, db = b[axis] - value;
    if ((da < 0.0) == (db < 0.0)) continue;
    (n++ == 0 ? p0 : p1) = a + (b - a) * (da / (da - db));
  }
  return n == 2;
}

// Cuts the segment p0 p1 (a box's local coordinates) to |coordinate| <= 1 on every axis but
// `axis`. False when nothing is left.
bool clipToFace(Eigen::Vector3d& p0, Eigen::Vector3d& p1, int axis) {
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector3d d = p1 - p0;
  for (int j = 0; j < 3; ++j) {
    if (j == axis) continue;
    for (int s = -1; s <= 1; s += 2) {  // s * (p0 + t d)[j] <= 1 + eps
      const double num = 1.0 + 1e-9 - s * p0[j], den = s * d[j];
      if (std::abs(den) < 1e-15) {
        if (num < 0.0) return false;
      } else if (den > 0.0) {
        t1 = std::min(t1, num / den);
      } else {
        t0 = std::max(t0, num / den);
      }
    }
  }
  if (t0 > t1) return false;
  const Eigen::Vector3d a = p0 + t0 * d, b = p0 + t1 * d;
  p0 = a, p1 = b;
  return true;
}

}  // namespace

// The post filter marks a pixel when its luma and its four diagonal neighbours' differ enough,
// so every pixel it marks lies within sqrt(2) px of a line across which the picture jumps. On a
// box (drawBox: flat faces, one material) such a line can only be one of its edges, where one
// of its faces meets the ground (the objects are clipped at the ground's plane, or hidden by it),
// or where it cuts into another box: the filter's region for a box is a band kBand px wide on
// each side of those lines (and past their ends), instead of its whole screen rectangle, most of
// which is a face or the ground (hopper_terrain's first block: 71,000 pixels of rectangle, about
// 8,000 of bands). What crosses a box is another draw, in its own rectangle: a hull's or the
// hair's edges, and a shadow's hard edge at its caster's contact. A box not wholly in front of
// the near plane, and every box among more than 64 draws (screenRects' union), keeps its
// rectangle.
void Renderer::Impl::postFilterRegions(const FramePlan& f, bool boxed, double shadow_reach,
                                       std::vector<LineVertex>& tris) const {
  tris.clear();
  const auto corner = [&](double x0, double y0, double x1, double y1) {  // a pixel rectangle
    const float X0 = float(x0 / f.w * 2.0 - 1.0), Y0 = float(y0 / f.h * 2.0 - 1.0);
    const float X1 = float(x1 / f.w * 2.0 - 1.0), Y1 = float(y1 / f.h * 2.0 - 1.0);
    for (const auto& [x, y] : {std::pair{X0, Y0}, {X1, Y0}, {X1, Y1}, {X0, Y0}, {X1, Y1}, {X0, Y1}})
      tris.push_back(LineVertex{{x, y, 0.0f}, {0.0f, 0.0f, 0.0f}});
  };
  if (!boxed) {
    corner(0, 0, f.w, f.h);
    return;
  }
  constexpr double kBand = 2.5;
  const Eigen::Matrix4d vp = f.view_proj.cast<double>();
  // Pixel coordinates (from the bottom left) of a world point in front of the near plane.
  const auto pixel = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector4d c = vp * p.homogeneous();
    return Eigen::Vector2d((c.x() / c.w() * 0.5 + 0.5) * f.w, (c.y() / c.w() * 0.5 + 0.5) * f.h);
  };
  const auto band = [&](const Eigen::Vector3d& a3, const Eigen::Vector3d& b3) {
    const Eigen::Vector2d a = pixel(a3), b = pixel(b3);
    const double len = (b - a).norm();
    const Eigen::Vector2d u = len > 1e-9 ? Eigen::Vector2d((b - a) / len) : Eigen::Vector2d(1.0, 0.0);
    const Eigen::Vector2d n(-u.y(), u.x());
    const Eigen::Vector2d q[4] = {a - kBand * (u + n), b + kBand * (u - n), b + kBand * (u + n), a - kBand * (u - n)};
    for (int i : {0, 1, 2, 0, 2, 3})
      tris.push_back(
          LineVertex{{float(q[i].x() / f.w * 2.0 - 1.0), float(q[i].y() / f.h * 2.0 - 1.0), 0.0f}, {0.0f, 0.0f, 0.0f}});
  };
  // The boxes that get bands: their model matrices and world corners.
  struct Box {
    Eigen::Matrix4d model, inverse;
    std::array<Eigen::Vector3d, 8> p;
    int part;
  };
  std::vector<Box> boxes;
  std::vector<char> skip(part_bounds.size(), 0);
  if (part_bounds.size() <= 64) {
    for (const MeshDraw& d : mesh_draws) {
      if (d.mesh != box_mesh || d.part < 0) continue;
      Box b;
      b.model = d.model.cast<double>();
      if (!(std::abs(b.model.topLeftCorner<3, 3>().determinant()) > 1e-18)) continue;
      b.inverse = b.model.inverse();
      b.part = d.part;
      bool front = true;
      for (int i = 0; i < 8; ++i) {
        b.p[size_t(i)] = (b.model * Eigen::Vector4d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1, 1)).head<3>();
        const Eigen::Vector4d c = vp * b.p[size_t(i)].homogeneous();
        front = front && c.w() > 1e-6 && c.z() >= -c.w();
      }
      if (!front) continue;
      boxes.push_back(b);
      skip[size_t(d.part)] = 1;
    }
  }
  // Every other draw and the lines: their screen rectangles (the whole frame when those are not
  // bounded).
  bool others = !lines.empty();
  for (size_t k = 0; k < part_bounds.size(); ++k) others = others || (!skip[k] && !part_bounds[k].isEmpty());
  if (others) {
    std::vector<PixelRect> own;
    if (screenRects(f.view_proj, f.w, f.h, own, &skip))
      for (const PixelRect& r : own) corner(r.x0, r.y0, r.x1, r.y1);
    else
      corner(0, 0, f.w, f.h);
  }
  // The other draws' shadows on a box: a hull's, the hair's or a mesh's penumbra can be marked
  // (the hopper's on a block it stands over). Each such caster's box swept along the light down
  // to the lowest box and grown by the shadow taps' reach over the light's slant holds its
  // shadow; where that meets a box's bounds, the screen rectangle of the meeting gets the filter.
  if (!boxes.empty() && f.shadows_on) {
    const Eigen::Vector3d l = f.light_dir;
    double zlow = std::numeric_limits<double>::infinity();
    for (const Box& b : boxes) zlow = std::min(zlow, part_bounds[size_t(b.part)].min().z());
    if (params.ground) zlow = std::min(zlow, params.ground_height);
    const auto screenRect = [&](const Eigen::AlignedBox3d& box, PixelRect& r) {
      double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector4d c = vp * box.corner(Eigen::AlignedBox3d::CornerType(i)).homogeneous();
        if (!(c.w() > 1e-6)) return false;
        const Eigen::Vector2d p = pixel(box.corner(Eigen::AlignedBox3d::CornerType(i)));
        x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
      }
      r = {std::clamp(int(std::floor(x0)) - 6, 0, f.w), std::clamp(int(std::floor(y0)) - 6, 0, f.h),
           std::clamp(int(std::ceil(x1)) + 6, 0, f.w), std::clamp(int(std::ceil(y1)) + 6, 0, f.h)};
      return true;
    };
    for (size_t k = 0; k < part_bounds.size(); ++k) {
      if (skip[k] || part_bounds[k].isEmpty()) continue;
      Eigen::AlignedBox3d swept = part_bounds[k];
      const bool bounded = l.z() < -0.05;
      if (bounded) {
        for (int i = 0; i < 8; ++i) {
          const Eigen::Vector3d p = part_bounds[k].corner(Eigen::AlignedBox3d::CornerType(i));
          if (p.z() > zlow) swept.extend(p + l * ((p.z() - zlow) / -l.z()));
        }
        const double grow = shadow_reach / -l.z();
        swept.min().array() -= grow;
        swept.max().array() += grow;
      }
      // Its shadow on the ground: the swept box's slab at the ground (within the reach).
      PixelRect on_ground{0, 0, 0, 0};
      if (params.ground && bounded) {
        Eigen::AlignedBox3d slab = swept;
        const double grow = shadow_reach / -l.z();
        slab.min().z() = std::max(slab.min().z(), params.ground_height - grow);
        slab.max().z() = std::min(slab.max().z(), params.ground_height + grow);
        if (!slab.isEmpty() && !screenRect(slab, on_ground)) on_ground = {0, 0, f.w, f.h};
      }
      for (const Box& b : boxes) {
        const Eigen::AlignedBox3d& bb = part_bounds[size_t(b.part)];
        PixelRect own;
        if (!screenRect(bb, own)) own = {0, 0, f.w, f.h};
        const PixelRect g = on_ground & own;
        if (!g.empty()) corner(g.x0, g.y0, g.x1, g.y1);
        if (bounded && !swept.intersects(bb)) continue;
        PixelRect r;
        if (!bounded || !screenRect(swept.intersection(bb), r)) r = own;
        if (!r.empty()) corner(r.x0, r.y0, r.x1, r.y1);
      }
    }
  }
  for (const Box& b : boxes) {
    for (int i = 0; i < 8; ++i)  // the edges
      for (int k = 0; k < 3; ++k)
        if (!(i & (1 << k))) band(b.p[size_t(i)], b.p[size_t(i | (1 << k))]);
    for (int k = 0; k < 3; ++k)
      for (int s = -1; s <= 1; s += 2) {
        const std::array<int, 4> face = boxFace(k, s);
        const std::array<Eigen::Vector3d, 4> q{b.p[size_t(face[0])], b.p[size_t(face[1])], b.p[size_t(face[2])],
                                               b.p[size_t(face[3])]};
        Eigen::Vector3d p0, p1;
        if (params.ground && quadCut(q, 2, params.ground_height, p0, p1)) band(p0, p1);  // the ground
        for (const Box& o : boxes) {  // another box: this face against each of its faces
          if (&o == &b || !part_bounds[size_t(b.part)].intersects(part_bounds[size_t(o.part)])) continue;
          std::array<Eigen::Vector3d, 4> local;
          for (int i = 0; i < 4; ++i) local[size_t(i)] = (o.inverse * q[size_t(i)].homogeneous()).head<3>();
          for (int ko = 0; ko < 3; ++ko)
            for (int so = -1; so <= 1; so += 2)
              if (quadCut(local, ko, double(so), p0, p1) && clipToFace(p0, p1, ko))
                band((o.model * p0.homogeneous()).head<3>(), (o.model * p1.homogeneous()).head<3>());
        }
      }
  }
}

void Renderer::Impl::mergeRects(std::vector<PixelRect>& rects, int64_t slack) {
  for (bool merged = true; merged;) {
    merged = false;
    for (size_t i = 0; i < rects.size() && !merged; ++i)
      for (size_t j = i + 1; j < rects.size() && !merged; ++j) {
        const PixelRect both = rects[i] | rects[j], common = rects[i] & rects[j];
        const int64_t overlap = common.empty() ? 0 : common.area();
        if (both.area() - (rects[i].area() + rects[j].area() - overlap) <= std::max(overlap, slack)) {
          rects[i] = both;
          rects.erase(rects.begin() + std::ptrdiff_t(j));
          merged = true;
        }
      }
  }
}

// Each caster's texel box: meshes by their transformed bounding boxes, the hulls by their spheres
// (one box for all of them: a body's hulls touch), the hair by its vertices and ribbon half widths
// (one box). A texel outside every box, grown by the farthest any tap reaches, sees no blocker.
void Renderer::Impl::casterTexelBoxes(const Eigen::Matrix4d& light_vp, double margin_m, int size,
                                      std::vector<PixelRect>& out, bool moving_only) const {
  out.clear();
  // For the orthographic light, light-space x and y are affine in the point and metres map to
  // the same number of texels on both axes.
  const Eigen::Matrix<double, 2, 4> A = light_vp.topRows<2>() * (0.5 * size);
  const double per_m = A.block<1, 3>(0, 0).norm();
  const double m = margin_m * per_m;
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  const auto add = [&](const Eigen::Vector3d& p, double r) {
    const Eigen::Vector2d t = A.leftCols<3>() * p + A.col(3) + Eigen::Vector2d::Constant(0.5 * size);
    const double rt = r * per_m;
    x0 = std::min(x0, t.x() - rt);
    x1 = std::max(x1, t.x() + rt);
    y0 = std::min(y0, t.y() - rt);
    y1 = std::max(y1, t.y() + rt);
  };
  const auto emit = [&] {
    if (x0 > x1) return;
    const PixelRect b{std::clamp(int(std::floor(x0 - m)), 0, size), std::clamp(int(std::floor(y0 - m)), 0, size),
                      std::clamp(int(std::ceil(x1 + m)), 0, size), std::clamp(int(std::ceil(y1 + m)), 0, size)};
    if (!b.empty()) out.push_back(b);
    x0 = y0 = 1e30;
    x1 = y1 = -1e30;
  };
  for (const MeshDraw& d : mesh_draws) {
    const Eigen::AlignedBox3d& b = meshes[size_t(d.mesh)].bbox;
    if (b.isEmpty() || (moving_only && d.still)) continue;
    const Eigen::Matrix4d M = d.model.cast<double>();
    for (int i = 0; i < 8; ++i) add((M * b.corner(Eigen::AlignedBox3d::CornerType(i)).homogeneous()).head<3>(), 0.0);
    emit();
  }
  for (const HullInstance& h : hulls) {
    add(Eigen::Vector3d(h.p0r0[0], h.p0r0[1], h.p0r0[2]), std::abs(double(h.p0r0[3])));
    add(Eigen::Vector3d(h.p1r1[0], h.p1r1[1], h.p1r1[2]), std::abs(double(h.p1r1[3])));
  }
  emit();
  const double min_half = 0.5 * frustum.texel_world;  // drawHairs' minimum half width in this pass
  for (const HairVertex& v : hair_vertices)
    add(Eigen::Vector3d(v.pos[0], v.pos[1], v.pos[2]), std::max(std::abs(double(v.half_width)), min_half));
  emit();
  // Many draws (a long chain of links): their union.
  if (out.size() > 64) {
    PixelRect u{0, 0, 0, 0};
    for (const PixelRect& r : out) u = u | r;
    out.assign(1, u);
  }
}

// Each caster's box in world space, as its 8 corners: a mesh draw's transformed bounding box,
// a hull's box around its two spheres, the box around the hair's vertices
// grown by their ribbon half widths (one); more than 64 of them: the box around them all.
void Renderer::Impl::casterCorners(std::vector<std::array<Eigen::Vector3d, 8>>& out) const {
  out.clear();
  const auto corners = [](const Eigen::AlignedBox3d& b) {
    std::array<Eigen::Vector3d, 8> c;
    for (int i = 0; i < 8; ++i) c[size_t(i)] = b.corner(Eigen::AlignedBox3d::CornerType(i));
    return c;
  };
  for (const MeshDraw& d : mesh_draws) {
    const Eigen::AlignedBox3d& b = meshes[size_t(d.mesh)].bbox;
    if (b.isEmpty()) continue;
    const Eigen::Matrix4d M = d.model.cast<double>();
    std::array<Eigen::Vector3d, 8> c = corners(b);
    for (Eigen::Vector3d& p : c) p = (M * p.homogeneous()).head<3>();
    out.push_back(c);
  }
  for (const HullInstance& h : hulls) {
    Eigen::AlignedBox3d hb;
    for (const float* s : {h.p0r0, h.p1r1}) {
      const Eigen::Vector3d c(s[0], s[1], s[2]);
      const double r = std::abs(double(s[3]));
      hb.extend(c - Eigen::Vector3d::Constant(r));
      hb.extend(c + Eigen::Vector3d::Constant(r));
    }
    out.push_back(corners(hb));
  }
  Eigen::AlignedBox3d hair;
  const double min_half = 0.5 * frustum.texel_world;  // drawHairs' minimum half width in the shadow pass
  for (const HairVertex& v : hair_vertices) {
    const Eigen::Vector3d c(v.pos[0], v.pos[1], v.pos[2]);
    const double r = std::max(std::abs(double(v.half_width)), min_half);
    hair.extend(c - Eigen::Vector3d::Constant(r));
    hair.extend(c + Eigen::Vector3d::Constant(r));
  }
  if (!hair.isEmpty()) out.push_back(corners(hair));
  if (out.size() > 64) {
    Eigen::AlignedBox3d all;
    for (const auto& c : out)
      for (const Eigen::Vector3d& p : c) all.extend(p);
    out.assign(1, corners(all));
  }
}

// Per caster (casterCorners): its corners carried along the light onto the ground (the ground
// points on the same light rays: the same light-space x and y), each grown to a square of the
// taps' reach on the ground (ground_shadow_reach over the light's slant: a distance d on the
// ground is at least d |light.z| in the light's view); their convex hull, cut at the camera's near
// plane, projected and bounded. Outside every such hull no tap of a ground point's shadow texel
// reaches a caster, so it reads 1. Tighter than the casters' light-space box carried onto the
// ground (hopper_terrain: that box holds the terrain's blocks and the hopper and is slanted onto
// the ground; 28 % of the frame at 1280x720 against 14.5 % for these).
bool Renderer::Impl::groundShadowRects(const Eigen::Matrix4f& view_proj, int w, int h, std::vector<PixelRect>& out,
                                       bool& whole) const {
  whole = false;
  out.clear();
  if (!ground_shadow_boxed || ground_shadow_size <= 0) return false;
  const Eigen::Vector3d& d = ground_shadow_light;
  if (d.z() > -1e-3) return whole = true;  // a light along the ground: no bound
  const double g = params.ground_height, reach = ground_shadow_reach / -d.z();
  std::vector<std::array<Eigen::Vector3d, 8>> casters;
  casterCorners(casters);
  std::vector<Eigen::Vector2d> pts, hull;
  for (const auto& c : casters) {
    pts.clear();
    for (const Eigen::Vector3d& p : c) {  // along the light onto the ground (back up it from below)
      const Eigen::Vector3d q = p + d * ((p.z() - g) / -d.z());
      for (double sx : {-reach, reach})
        for (double sy : {-reach, reach}) pts.emplace_back(q.x() + sx, q.y() + sy);
    }
    // The convex hull (monotone chain), counter-clockwise.
    std::sort(pts.begin(), pts.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
    });
    hull.assign(2 * pts.size(), Eigen::Vector2d::Zero());
    size_t k = 0;
    const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
    };
    for (size_t i = 0; i < pts.size(); ++i) {
      while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.0) --k;
      hull[k++] = pts[i];
    }
    for (size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
      while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i - 1]) <= 0.0) --k;
      hull[k++] = pts[i - 1];
    }
    hull.resize(k > 1 ? k - 1 : k);
    // Cut at the near plane (z >= -w in clip space; clip coordinates are affine along the
    // hull's edges): a part behind the eye is not on screen, and what is left projects to a
    // bounded rectangle. Nothing left: this shadow is nowhere on screen.
    const Eigen::Matrix4d vp = view_proj.cast<double>();
    double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
    bool any = false;
    const auto put = [&](const Eigen::Vector4d& v) {
      if (v.w() < 1e-9) return false;  // only with a degenerate near plane
      const double px = (v.x() / v.w() * 0.5 + 0.5) * w, py = (v.y() / v.w() * 0.5 + 0.5) * h;
      x0 = std::min(x0, px);
      x1 = std::max(x1, px);
      y0 = std::min(y0, py);
      y1 = std::max(y1, py);
      any = true;
      return true;
    };
    const size_t n = hull.size();
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector4d p = vp * Eigen::Vector4d(hull[i].x(), hull[i].y(), g, 1.0);
      const Eigen::Vector4d q = vp * Eigen::Vector4d(hull[(i + 1) % n].x(), hull[(i + 1) % n].y(), g, 1.0);
      const double dp = p.z() + p.w(), dq = q.z() + q.w();
      if (dp >= 0.0 && !put(p)) return whole = true;
      if ((dp >= 0.0) != (dq >= 0.0) && !put(p + (q - p) * (dp / (dp - dq)))) return whole = true;
    }
    if (!any) continue;
    // Clamped before the cast: a point just past the near plane projects far off screen.
    x0 = std::clamp(x0, -2.0, w + 2.0), x1 = std::clamp(x1, -2.0, w + 2.0);
    y0 = std::clamp(y0, -2.0, h + 2.0), y1 = std::clamp(y1, -2.0, h + 2.0);
    const PixelRect r{std::clamp(int(std::floor(x0)) - 1, 0, w), std::clamp(int(std::floor(y0)) - 1, 0, h),
                      std::clamp(int(std::ceil(x1)) + 1, 0, w), std::clamp(int(std::ceil(y1)) + 1, 0, h)};
    if (!r.empty()) out.push_back(r);
  }
  mergeRects(out, 0);
  return !out.empty();
}

bool Renderer::Impl::groundShadowRect(const Eigen::Matrix4f& view_proj, int w, int h, PixelRect& rect,
                                      bool& whole) const {
  std::vector<PixelRect> rs;
  if (!groundShadowRects(view_proj, w, h, rs, whole)) return false;
  rect = PixelRect{0, 0, 0, 0};
  for (const PixelRect& r : rs) rect = rect | r;
  return true;
}

void Renderer::Impl::partitionRects(const std::vector<PixelRect>& rects, const PixelRect& clip,
                                    std::vector<PixelRect>& inside, std::vector<PixelRect>& outside) {
  inside.clear();
  outside.clear();
  if (clip.empty()) return;
  std::vector<int> ys{clip.y0, clip.y1};
  for (const PixelRect& r : rects) {
    const PixelRect c = r & clip;
    if (c.empty()) continue;
    ys.push_back(c.y0);
    ys.push_back(c.y1);
  }
  std::sort(ys.begin(), ys.end());
  ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
  // A piece of this band joins the rectangle right below it when their columns match.
  const auto put = [](std::vector<PixelRect>& list, const PixelRect& r) {
    if (r.empty()) return;
    for (PixelRect& o : list)
      if (o.x0 == r.x0 && o.x1 == r.x1 && o.y1 == r.y0) {
        o.y1 = r.y1;
        return;
      }
    list.push_back(r);
  };
  std::vector<std::pair<int, int>> spans;
  for (size_t k = 0; k + 1 < ys.size(); ++k) {
    const int ya = ys[k], yb = ys[k + 1];
    spans.clear();
    for (const PixelRect& r : rects) {
      const PixelRect c = r & clip;
      if (!c.empty() && c.y0 <= ya && c.y1 >= yb) spans.emplace_back(c.x0, c.x1);
    }
    std::sort(spans.begin(), spans.end());
    int x = clip.x0;
    for (size_t i = 0; i < spans.size();) {
      int a = spans[i].first, b = spans[i].second;
      for (++i; i < spans.size() && spans[i].first <= b; ++i) b = std::max(b, spans[i].second);
      put(outside, PixelRect{x, ya, a, yb});
      put(inside, PixelRect{a, ya, b, yb});
      x = b;
    }
    put(outside, PixelRect{x, ya, clip.x1, yb});
  }
}

}  // namespace ponyhop

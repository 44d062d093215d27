// Headless rendering: a lit, shadowed, anti-aliased, deterministic frame (OSMesa llvmpipe).
#include "engine/renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <numeric>

#include "common/out_util.h"
#include "engine/camera.h"
#include "engine/frame_writer.h"
#include "engine/gl_context.h"
#include "engine/hair.h"
#include "engine/image.h"
#include "engine/image_diff.h"
#include "engine/mesh.h"

using namespace ponyhop;

namespace {

constexpr int kW = 320, kH = 240;

// One context + renderer for the whole file (creating an OSMesa context per test is slow).
struct Gl {
  std::unique_ptr<HeadlessContext> ctx;
  std::unique_ptr<Renderer> renderer;
  std::string error;
};
Gl& gl() {
  static Gl g = [] {
    Gl x;
    x.ctx = HeadlessContext::create(kW, kH, &x.error);
    if (x.ctx) {
      x.renderer = std::make_unique<Renderer>();
      if (!x.renderer->init(&x.error)) x.renderer.reset();
    }
    return x;
  }();
  return g;
}

using ponyhop::testing::outFolder;

// A camera at `eye` looking at `target`, with a vertical field of view of `fov` degrees.
Camera cameraAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double fov = Camera().fov) {
  Camera c;
  c.eye = eye;
  c.target = target;
  c.fov = fov;
  return c;
}

Camera testCamera() { return cameraAt(Eigen::Vector3d(0.9, -1.4, 0.55), Eigen::Vector3d(0.0, 0.0, 0.15), 35.0); }

RenderParams testParams(int samples = 4, bool ground = true) {
  RenderParams p;
  p.width = kW;
  p.height = kH;
  p.samples = samples;
  p.ground = ground;
  return p;
}

LightParams testLight() {
  LightParams l;
  l.shadow_size = 1024;
  return l;
}

const Eigen::Vector3d kSphereC(0.0, 0.0, 0.2);
constexpr double kSphereR = 0.15;

Material red() {
  Material m;
  m.color = Eigen::Vector3f(0.85f, 0.25f, 0.2f);
  return m;
}

// Renders; `scene` draws into the renderer between beginFrame and endFrame.
template <class F>
std::vector<uint8_t> render(const Camera& cam, const RenderParams& rp, F&& scene, const LightParams& l = testLight()) {
  Renderer& r = *gl().renderer;
  r.beginFrame(cam, l, rp);
  scene(r);
  r.endFrame();
  std::vector<uint8_t> px;
  r.readPixels(px);
  return px;
}

double luminance(const std::vector<uint8_t>& px, int x, int y, int w = kW) {
  const uint8_t* p = px.data() + (size_t(y) * size_t(w) + size_t(x)) * 4;
  return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

// Pixel (x right, y down) of a world point.
Eigen::Vector2d project(const Camera& cam, const Eigen::Vector3d& p, int w = kW, int h = kH) {
  const Eigen::Vector4d c = cam.projection(double(w) / h, 0.1, 10.0) * cam.view() * p.homogeneous();
  const Eigen::Vector2d ndc = c.head<2>() / c.w();
  return {(ndc.x() * 0.5 + 0.5) * w, (0.5 - ndc.y() * 0.5) * h};
}

// The shadow tests' comparison of a frame with the forward (4x MSAA) one at sampled pixels: the
// forward frame's luminance there and how far the other frame's differs.
struct LuminanceSamples {
  std::vector<double> forward, diff;
  // The pixel under screen point p, unless it is on the frame's border.
  void add(const std::vector<uint8_t>& fwd, const std::vector<uint8_t>& other, const Eigen::Vector2d& p) {
    const int px = int(p.x()), py = int(p.y());
    if (px < 1 || py < 1 || px > kW - 2 || py > kH - 2) return;
    forward.push_back(luminance(fwd, px, py));
    diff.push_back(std::abs(luminance(other, px, py) - forward.back()));
  }
  // How many samples lie in [lo, hi) times the brightest one.
  long between(double lo, double hi) const {
    const double lit = *std::max_element(forward.begin(), forward.end());
    return std::count_if(forward.begin(), forward.end(), [&](double l) { return l >= lo * lit && l < hi * lit; });
  }
  double worst() const { return *std::max_element(diff.begin(), diff.end()); }
};

void save(const std::string& name, const std::vector<uint8_t>& px, int w = kW, int h = kH) {
  std::string err;
  EXPECT_TRUE(writePngAtomic(outFolder("renderer") + "/" + name, w, h, px.data(), &err)) << err;
}

#define REQUIRE_GL()                                       \
  do {                                                     \
    ASSERT_TRUE(gl().renderer) << "no GL: " << gl().error; \
  } while (0)

}  // namespace

TEST(Renderer, ContextIsCoreProfile33OrNewer) {
  REQUIRE_GL();
  const std::string v = gl().ctx->version();
  EXPECT_NE(v.find("Core"), std::string::npos) << v;
  EXPECT_GE(std::atof(v.c_str()), 3.3) << v;
  EXPECT_FALSE(gl().ctx->rendererName().empty());
}

TEST(Renderer, LitSphereCoversItsDiscAndIsShaded) {
  REQUIRE_GL();
  const Camera cam = testCamera();
  const RenderParams rp = testParams(4, /*ground=*/false);
  const auto empty = render(cam, rp, [](Renderer&) {});
  const auto img = render(cam, rp, [](Renderer& r) { r.drawSphere(kSphereC, kSphereR, red()); });
  save("sphere_no_ground.png", img);

  // Pixels that changed = the sphere. Its projected disc: radius ~ f * r / distance.
  auto changed = [&](int x, int y) {
    const size_t i = (size_t(y) * kW + size_t(x)) * 4;
    return std::abs(img[i] - empty[i]) + std::abs(img[i + 1] - empty[i + 1]) + std::abs(img[i + 2] - empty[i + 2]) > 12;
  };
  int covered = 0;
  std::vector<double> lum;  // interior pixels only (3 px from the silhouette: no edge blending)
  for (int y = 3; y < kH - 3; ++y)
    for (int x = 3; x < kW - 3; ++x) {
      if (!changed(x, y)) continue;
      ++covered;
      bool interior = true;
      for (int dy = -3; dy <= 3 && interior; ++dy)
        for (int dx = -3; dx <= 3 && interior; ++dx) interior = changed(x + dx, y + dy);
      if (interior) lum.push_back(luminance(img, x, y));
    }
  const double dist = (kSphereC - cam.eye).norm();
  const double f_px = 0.5 * kH / std::tan(cam.fov * M_PI / 360.0);
  const double expected = M_PI * std::pow(f_px * kSphereR / dist, 2);
  EXPECT_GT(covered, 0.8 * expected);
  EXPECT_LT(covered, 1.2 * expected);

  // Lit, not flat: a real spread of brightness across the disc, neither black nor blown out.
  ASSERT_FALSE(lum.empty());
  const auto [mn, mx] = std::minmax_element(lum.begin(), lum.end());
  const double mean = std::accumulate(lum.begin(), lum.end(), 0.0) / double(lum.size());
  EXPECT_GT(*mx - *mn, 80.0);
  EXPECT_GT(mean, 50.0);
  EXPECT_LT(mean, 230.0);

  // The disc is where the projection says (also checks that rows come out top-down).
  const Eigen::Vector2d c = project(cam, kSphereC);
  const Eigen::Vector2d top = project(cam, kSphereC + Eigen::Vector3d(0, 0, 0.8 * kSphereR));
  for (const Eigen::Vector2d& p : {c, top}) {
    const size_t i = (size_t(p.y()) * kW + size_t(p.x())) * 4;
    EXPECT_GT(std::abs(img[i] - empty[i]) + std::abs(img[i + 1] - empty[i + 1]), 20) << p.transpose();
  }
}

TEST(Renderer, ShadowDarkensTheGroundUnderTheSphere) {
  REQUIRE_GL();
  const Camera cam = testCamera();
  const RenderParams rp = testParams(4, true);
  LightParams light = testLight();
  light.direction = Eigen::Vector3d(1.0, 0.3, -1.0);  // shadow falls to +x: in view, beside the sphere
  const auto empty = render(
      cam, rp, [](Renderer&) {}, light);
  const auto img = render(
      cam, rp, [](Renderer& r) { r.drawSphere(kSphereC, kSphereR, red()); }, light);
  save("sphere_shadow.png", img);
  save("empty_ground.png", empty);
  // Where the light ray through the centre meets z = 0: the middle of the shadow.
  const Eigen::Vector3d d = light.direction.normalized();
  const Eigen::Vector3d hit = kSphereC + d * (kSphereC.z() / -d.z());
  const Eigen::Vector2d p = project(cam, hit);
  ASSERT_TRUE(p.x() > 2 && p.x() < kW - 3 && p.y() > 2 && p.y() < kH - 3) << p.transpose();
  // ... and not hidden behind the sphere itself.
  const Eigen::Vector2d c = project(cam, kSphereC);
  const double r_px = (project(cam, kSphereC + cam.view().block<1, 3>(1, 0).transpose() * kSphereR) - c).norm();
  ASSERT_GT((p - c).norm(), r_px * 1.2);
  const double shadowed = luminance(img, int(p.x()), int(p.y()));
  const double lit = luminance(empty, int(p.x()), int(p.y()));
  EXPECT_LT(shadowed, 0.7 * lit) << "shadow " << shadowed << " vs lit ground " << lit;
  EXPECT_GT(shadowed, 15.0) << "shadow should not be black (ambient + fill)";

  // Contact: the shadow reaches the ground right below the sphere's lowest point on the light
  // side (no peter-panning) -- the point 1 cm from the shadow's start along the light.
  const Eigen::Vector3d bottom = kSphereC - Eigen::Vector3d(0, 0, kSphereR);
  const Eigen::Vector2d pc = project(cam, bottom + Eigen::Vector3d(d.x(), d.y(), 0).normalized() * 0.03);
  EXPECT_LT(luminance(img, int(pc.x()), int(pc.y())), 0.8 * luminance(empty, int(pc.x()), int(pc.y())));

  // No acne: lit ground away from the shadow is unchanged by the caster.
  const Eigen::Vector2d q = project(cam, Eigen::Vector3d(-0.3, -0.3, 0.0));
  double worst = 0.0;
  for (int y = int(q.y()) - 4; y < int(q.y()) + 4; ++y)
    for (int x = int(q.x()) - 4; x < int(q.x()) + 4; ++x)
      worst = std::max(worst, std::abs(luminance(img, x, y) - luminance(empty, x, y)));
  EXPECT_LT(worst, 3.0) << "lit ground changed by a far caster: acne or a misplaced shadow";
}

// The ground hides what is below it in every anti-aliasing mode: the full-resolution ground by its
// depth (MSAA), the half-resolution one, upsampled before the objects, by clipping them at its
// plane (no AA, the post filter).
TEST(Renderer, TheGroundHidesWhatIsBelowIt) {
  REQUIRE_GL();
  for (const AntiAlias aa : {AntiAlias::Post, AntiAlias::Msaa}) {
    for (const int samples : {1, 4}) {
      RenderParams rp = testParams(samples, true);
      rp.antialias = aa;
      const auto empty = render(testCamera(), rp, [](Renderer&) {});
      const auto below = render(testCamera(), rp, [](Renderer& r) {
        r.drawSphere(Eigen::Vector3d(0.0, 0.0, -0.2), 0.15, red());
        r.drawCapsule({0.1, 0.1, -0.4}, {0.1, 0.1, -0.07}, 0.05, red());  // top at z = -0.02
      });
      // The same sphere and capsule lifted above the ground are in view (the test looks at them).
      const auto above = render(testCamera(), rp, [](Renderer& r) {
        r.drawSphere(Eigen::Vector3d(0.0, 0.0, 0.2), 0.15, red());
        r.drawCapsule({0.1, 0.1, 0.07}, {0.1, 0.1, 0.4}, 0.05, red());
      });
      double worst = 0.0, seen = 0.0;
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
          worst = std::max(worst, std::abs(luminance(below, x, y) - luminance(empty, x, y)));
          seen = std::max(seen, std::abs(luminance(above, x, y) - luminance(empty, x, y)));
        }
      EXPECT_LT(worst, 2.0) << "samples " << samples << ": something below the ground shows through it";
      EXPECT_GT(seen, 40.0) << "samples " << samples << ": the objects above the ground are not in view";
      if (samples == 4 && aa == AntiAlias::Post) save("below_ground.png", below);
    }
  }
}

// The shadow map is reused from frame to frame. What a frame shows must not depend on what the
// frames before it drew: (1) a caster gone since the last frame leaves no depth behind; (2) the
// first frame on a new or resized map reads no blocker where none is. Any scheme that clears or
// caches less than the whole map each frame must keep both (one that cleared only this frame's
// caster box failed both checks). All frames keep the same light frustum (setShadowBounds), and
// the slab of one frame lies just beside the sphere of the next, within reach of its shadow
// lookups but outside its caster box.
TEST(Renderer, ACasterGoneSinceTheLastFrameLeavesNoShadow) {
  REQUIRE_GL();
  const Camera cam = testCamera();
  const Eigen::AlignedBox3d bounds(Eigen::Vector3d(-0.6, -0.6, 0.0), Eigen::Vector3d(0.6, 0.6, 0.6));
  constexpr double kR = 0.1;
  const auto sphere = [&](Renderer& r) {
    r.setShadowBounds(bounds);
    r.drawSphere(kSphereC, kR, red());
  };
  const auto slab = [&](Renderer& r) {
    r.setShadowBounds(bounds);
    r.drawBox(Eigen::Affine3d(Eigen::Translation3d(0.13, 0.0, 0.2)), Eigen::Vector3d(0.01, 0.12, 0.12), red());
  };
  const auto nothing = [&](Renderer& r) { r.setShadowBounds(bounds); };
  // A map of another size first, so that the frames below start from a new, never cleared one.
  LightParams other = testLight();
  other.shadow_size = testLight().shadow_size / 4;  // below the 512 the matched map never goes under
  render(cam, testParams(), sphere, other);
  const auto first_sphere = render(cam, testParams(), sphere);
  render(cam, testParams(), slab);
  const auto after_slab = render(cam, testParams(), sphere);
  const auto after_sphere = render(cam, testParams(), sphere);
  const auto lit = render(cam, testParams(), nothing);
  save("gone_first_sphere.png", first_sphere);
  save("gone_after_slab.png", after_slab);
  save("gone_after_sphere.png", after_sphere);
  ASSERT_EQ(after_slab.size(), after_sphere.size());
  EXPECT_TRUE(after_slab == after_sphere) << "the slab's shadow is still there a frame later";
  EXPECT_TRUE(first_sphere == after_sphere) << "the first frame on a new shadow map differs";

  // (2) in absolute terms: the ground 6 cm outside the sphere's shadow cylinder (past the widest
  // penumbra, 3 cm, yet within the reach of the ground's shadow lookups) is lit, all around it.
  const Eigen::Vector3d d = LightParams().direction.normalized();
  const Eigen::Vector3d hit = kSphereC + d * (kSphereC.z() / -d.z());
  const Eigen::Vector2d c = project(cam, kSphereC);
  const double r_px = (project(cam, kSphereC + cam.view().block<1, 3>(1, 0).transpose() * kR) - c).norm();
  int checked = 0;
  for (int k = 0; k < 16; ++k) {
    const double a = 2.0 * M_PI * k / 16.0;
    const Eigen::Vector3d w(std::cos(a), std::sin(a), 0.0);
    const double across = (w - w.dot(d) * d).norm();  // distance from the axis per metre along w
    const Eigen::Vector3d g = hit + w * ((kR + 0.06) / across);
    const Eigen::Vector2d p = project(cam, g);
    if ((p - c).norm() < r_px + 3.0 || p.x() < 1 || p.y() < 1 || p.x() > kW - 2 || p.y() > kH - 2) continue;
    ++checked;
    for (const auto* img : {&first_sphere, &after_slab}) {
      const double dl = luminance(*img, int(p.x()), int(p.y())) - luminance(lit, int(p.x()), int(p.y()));
      EXPECT_LT(std::abs(dl), 3.0) << "ground at " << g.transpose() << " (pixel " << p.transpose()
                                   << ") is shadowed by no caster: " << dl;
    }
  }
  EXPECT_GE(checked, 10);
}

// The shadow map has no more texels than the frame shows over the casters (light.shadow_match,
// resolutionMatchedShadowSize in frame_plan.cpp): fewer for a small or distant view, all of
// shadow_size for a close one or with hair, never fewer than 512 nor more than shadow_size, half in
// draft; off, always shadow_size. And the matched map's picture passes the snapshot comparator
// against the full map's.
TEST(Renderer, ShadowMapMatchesTheFrame) {
  REQUIRE_GL();
  Renderer& r = *gl().renderer;
  // Shadow bounds 1 m wide (as a scene's fixed box would be): enough texels at 720p to match.
  const Eigen::AlignedBox3d bounds(Eigen::Vector3d(-0.5, -0.5, 0.0), Eigen::Vector3d(0.5, 0.5, 0.5));
  const auto sphere = [&](Renderer& rr) {
    rr.setShadowBounds(bounds);
    rr.drawSphere(kSphereC, kSphereR, red());
  };
  const auto frame = [&](const Camera& cam, int w, int h, const LightParams& l,
                         RenderQuality q = RenderQuality::Final) {
    RenderParams rp = testParams(1, true);
    rp.width = w;
    rp.height = h;
    rp.quality = q;
    std::vector<uint8_t> px = render(cam, rp, sphere, l);
    return std::make_pair(r.stats().shadow_size, std::move(px));
  };
  const LightParams light = testLight();  // shadow_size 1024
  Camera view = testCamera();             // farther out: 1280x720 shows fewer than 1024 texels of the box
  view.eye = view.target + (view.eye - view.target) * 2.0;
  Camera close = testCamera();
  close.eye = kSphereC + (testCamera().eye - kSphereC).normalized() * 0.6;
  close.target = kSphereC;

  const int small = frame(view, 320, 180, light).first;
  const int hd = frame(view, 1280, 720, light).first;
  const int full_hd = frame(view, 1920, 1080, light).first;
  EXPECT_EQ(small, 512) << "a small frame takes the fewest texels";
  EXPECT_GT(hd, small) << "a larger frame of the same view takes more (" << small << ", " << hd << ", " << full_hd
                       << ")";
  EXPECT_GT(full_hd, hd);
  EXPECT_LT(hd, 1024) << "1280x720 of this view shows fewer than 1024 texels over the sphere";
  EXPECT_EQ(frame(close, 1920, 1080, light).first, 1024) << "a close-up takes all of shadow_size";
  EXPECT_EQ(frame(view, 320, 180, light, RenderQuality::Draft).first, 256) << "draft: half";
  LightParams fixed = light;
  fixed.shadow_match = false;
  EXPECT_EQ(frame(view, 320, 180, fixed).first, 1024);
  // A strand of hair in the picture: the whole map (its shadow depends on the texel's size).
  HairMesh strand;
  for (int i = 0; i < 4; ++i) {
    HairVertex v{};
    v.pos[0] = 0.2f;
    v.pos[1] = 0.0f;
    v.pos[2] = 0.1f + 0.1f * float(i / 2);
    v.tangent[2] = 1.0f;
    v.normal[0] = 1.0f;
    v.color[0] = v.color[1] = v.color[2] = 0.3f;
    v.half_width = i % 2 ? 0.001f : -0.001f;
    v.occlusion = 1.0f;
    strand.vertices.push_back(v);
  }
  strand.indices = {0, 1, 2, 1, 3, 2};
  RenderParams small_rp = testParams(1, true);
  small_rp.width = 320;
  small_rp.height = 180;
  render(
      view, small_rp,
      [&](Renderer& rr) {
        sphere(rr);
        rr.drawHair(strand);
      },
      light);
  EXPECT_EQ(r.stats().shadow_size, 1024) << "hair keeps shadow_size";
  LightParams few = light;
  few.shadow_size = 300;
  EXPECT_EQ(frame(close, 1920, 1080, few).first, 300) << "never more than shadow_size";
  EXPECT_EQ(frame(view, 320, 180, few).first, 300) << "nor the 512 floor above it";

  // The look: 1280x720 with the matched map against the full one.
  Image matched, full;
  matched.width = full.width = 1280;
  matched.height = full.height = 720;
  matched.rgba = frame(view, 1280, 720, light).second;
  full.rgba = frame(view, 1280, 720, fixed).second;
  ASSERT_NE(matched.rgba, full.rgba) << "the two maps made the same picture: is the matched one in use?";
  const DiffResult d = compareImages(full, matched, DiffOptions{});
  EXPECT_TRUE(d.pass) << d.message;
  save("matched_shadow_720p.png", matched.rgba, 1280, 720);
}

// A single-sample frame draws the rows above the horizon with the background's own pass rather
// than the half-resolution ground's upsampling (frame_plan.cpp, FramePlan::sky_row): they must be the
// background a frame without a ground has, and the frame must have no seam where the two meet:
// down every column the colour changes smoothly from the sky into the ground.
TEST(Renderer, TheSkyAboveTheHorizonIsTheBackgroundWithoutASeam) {
  REQUIRE_GL();
  const Camera cam = cameraAt(Eigen::Vector3d(0.0, -2.0, 0.45), Eigen::Vector3d(0.0, 0.0, 0.25), 40.0);
  const auto nothing = [](Renderer&) {};
  const auto ground = render(cam, testParams(1, true), nothing);
  const auto sky = render(cam, testParams(1, false), nothing);
  save("sky_ground.png", ground);
  // The horizon's row (from the top): where horizontal directions project.
  const Eigen::Vector4d c =
      cam.projection(double(kW) / kH, 0.1, 10.0) * cam.view() * Eigen::Vector4d(0.0, 1.0, 0.0, 0.0);
  const double horizon = (0.5 - 0.5 * c.y() / c.w()) * kH;
  ASSERT_GT(horizon, 20.0);
  ASSERT_LT(horizon, kH - 20.0);
  double worst_sky = 0.0, worst_step = 0.0;
  for (int x = 0; x < kW; x += 7) {
    for (int y = 0; y < int(horizon) - 3; ++y)
      worst_sky = std::max(worst_sky, std::abs(luminance(ground, x, y) - luminance(sky, x, y)));
    for (int y = 0; y + 1 < kH; ++y)
      worst_step = std::max(worst_step, std::abs(luminance(ground, x, y + 1) - luminance(ground, x, y)));
  }
  EXPECT_LE(worst_sky, 1.0) << "the sky is not the background";
  // The checker's edges are box-filtered: under 3 levels a row here; cut 40 rows into the
  // ground, the sky leaves a step of 8.
  EXPECT_LT(worst_step, 4.5) << "a seam between the sky and the ground";
}

// A single-sample frame shades its objects deferred, in two passes (deferredLightPass): the pixels that
// need no shadow filter (fully lit, or no key light) first, then the filter on the rest. The
// shadow on an object must come out as the forward shading (4x MSAA) computes it, pixel centre
// for pixel centre: lit, penumbra and umbra of a sphere's shadow on a box's top.
TEST(Renderer, DeferredShadowsOnObjectsMatchTheForwardOnes) {
  REQUIRE_GL();
  const Camera cam = testCamera();
  LightParams light = testLight();
  light.direction = Eigen::Vector3d(1.0, 0.3, -1.0);
  Material grey;
  grey.color = Eigen::Vector3f(0.7f, 0.7f, 0.7f);
  const Eigen::Vector3d ball(0.0, 0.0, 0.3);
  constexpr double kBallR = 0.08, kTop = 0.1;
  const auto scene = [&](Renderer& r) {
    r.drawBox(Eigen::Affine3d(Eigen::Translation3d(0.1, 0.0, kTop / 2)), Eigen::Vector3d(0.3, 0.3, kTop / 2), grey);
    r.drawSphere(ball, kBallR, red());
  };
  const auto deferred = render(cam, testParams(1, true), scene, light);
  RenderParams msaa = testParams(4, true);
  msaa.antialias = AntiAlias::Msaa;
  const auto forward = render(cam, msaa, scene, light);
  save("deferred_box.png", deferred);
  save("forward_box.png", forward);
  // Points of the box's top, inset from its edges, not behind or beside the ball on screen.
  const Eigen::Vector2d c = project(cam, ball);
  const double r_px = (project(cam, ball + cam.view().block<1, 3>(1, 0).transpose() * kBallR) - c).norm();
  LuminanceSamples samples;
  for (double x = -0.17; x <= 0.37; x += 0.01)
    for (double y = -0.27; y <= 0.27; y += 0.01) {
      const Eigen::Vector2d p = project(cam, Eigen::Vector3d(x, y, kTop));
      if ((p - c).norm() >= r_px + 3.0) samples.add(forward, deferred, p);
    }
  ASSERT_GT(samples.diff.size(), 500u);
  EXPECT_GT(samples.between(0.97, 1.01), 300) << "lit points on the box";
  EXPECT_GT(samples.between(0.0, 0.6), 20) << "points in the ball's shadow on the box";
  EXPECT_GT(samples.between(0.6, 0.95), 3) << "points in its penumbra";
  const double worst = samples.worst();
  EXPECT_LT(worst, 3.0) << "the deferred shadow differs from the forward one by " << worst << " (0-255 luminance)";
}

// The deferred shading (and the convex casters' lit colour) encodes its colour with
// linearToSrgbFast(), three square roots instead of pow(); the forward shading keeps the exact
// curve. On a matte sphere's inside, where every pixel's four MSAA samples see nearly the same
// radiance, both frames must agree to a level in nearly every channel, over colours from the lit
// side to the dark one. (The half-float key and rest and the self-shadow's terminator, where the
// four samples differ, move a few channels by more: 70 of 7,680 here; with one of the fit's
// coefficients off by 0.01, 5,338.)
TEST(Renderer, TheDeferredShadingsColourCurveIsWithinALevelOfTheExactOne) {
  REQUIRE_GL();
  const Camera cam = testCamera();
  Material matte;
  matte.color = Eigen::Vector3f(0.9f, 0.55f, 0.25f);
  matte.specular = 0.0f;
  matte.rim = 0.0f;
  const auto scene = [&](Renderer& r) { r.drawSphere(kSphereC, kSphereR, matte); };
  const auto deferred = render(cam, testParams(1, false), scene);
  RenderParams msaa = testParams(4, false);
  msaa.antialias = AntiAlias::Msaa;
  const auto forward = render(cam, msaa, scene);
  save("curve_deferred.png", deferred);
  save("curve_forward.png", forward);
  const Eigen::Vector2d c = project(cam, kSphereC);
  const double r_px = (project(cam, kSphereC + cam.view().block<1, 3>(1, 0).transpose() * kSphereR) - c).norm();
  int n = 0, over1 = 0, worst = 0, lo = 255, hi = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      if ((Eigen::Vector2d(x + 0.5, y + 0.5) - c).norm() > 0.85 * r_px) continue;
      const size_t i = (size_t(y) * kW + size_t(x)) * 4;
      for (int k = 0; k < 3; ++k) {
        const int d = std::abs(int(deferred[i + size_t(k)]) - int(forward[i + size_t(k)]));
        worst = std::max(worst, d);
        over1 += d > 1;
        lo = std::min(lo, int(forward[i + size_t(k)]));
        hi = std::max(hi, int(forward[i + size_t(k)]));
      }
      ++n;
    }
  ASSERT_GT(n, 1000);
  EXPECT_LT(lo, 60) << "the dark side is in the frame";
  EXPECT_GT(hi, 200) << "the lit side is in the frame";
  EXPECT_LT(over1, n / 10) << over1 << " channels of " << n << " pixels differ by more than a level (worst " << worst
                           << ")";
}

// The shadow mark (deferredRects): a convex caster's pixels that no other caster's light-space box
// reaches are finished by the objects pass, the others by the deferred shading. A ball's shadow
// on a lying capsule (hull on hull) and another's on a box (hull on mesh), penumbra and all, must
// come out as the forward shading (4x MSAA) computes it, and so must the lit points the objects
// pass finishes.
TEST(Renderer, ShadowMarkLeavesNoShadowedPixelLit) {
  REQUIRE_GL();
  const Camera cam = cameraAt(Eigen::Vector3d(-0.15, -1.5, 0.9), Eigen::Vector3d(-0.15, 0.0, 0.12), 28.0);
  LightParams light = testLight();
  light.direction = Eigen::Vector3d(0.6, 0.2, -1.0);
  Material grey;
  grey.color = Eigen::Vector3f(0.7f, 0.7f, 0.7f);
  constexpr double kTop = 0.1, kAxisZ = 0.08, kCapR = 0.07, kBallR = 0.04;
  // Each ball 0.3 m above its receiver, moved back along the light so that its shadow's centre
  // lies on the receiver's top (a penumbra several pixels wide: the forward frame's four samples
  // average a pixel the deferred shading takes at its centre).
  const Eigen::Vector3d on_capsule(-0.45, -0.08, kAxisZ + kCapR + 0.3), on_box(-0.02, -0.06, kTop + 0.3);
  const auto scene = [&](Renderer& r) {
    r.drawBox(Eigen::Affine3d(Eigen::Translation3d(0.2, 0.0, kTop / 2)), Eigen::Vector3d(0.16, 0.2, kTop / 2), grey);
    r.drawCapsule(Eigen::Vector3d(-0.6, 0.0, kAxisZ), Eigen::Vector3d(-0.1, 0.0, kAxisZ), kCapR, grey);
    r.drawSphere(on_capsule, kBallR, red());
    r.drawSphere(on_box, kBallR, red());
  };
  const auto marked = render(cam, testParams(1, true), scene, light);
  ASSERT_TRUE(gl().renderer->stats().shadow_marked) << "the frame was not marked: nothing here tests the mark";
  RenderParams msaa = testParams(4, true);
  msaa.antialias = AntiAlias::Msaa;
  const auto forward = render(cam, msaa, scene, light);
  save("marked_shadows.png", marked);
  save("marked_shadows_forward.png", forward);
  // Points of the box's top and of the capsule's upper side, not near the balls on screen.
  std::vector<Eigen::Vector2d> balls;
  std::vector<double> radii;
  for (const Eigen::Vector3d& b : {on_capsule, on_box}) {
    balls.push_back(project(cam, b));
    radii.push_back((project(cam, b + cam.view().block<1, 3>(1, 0).transpose() * kBallR) - balls.back()).norm());
  }
  LuminanceSamples samples;
  const auto sample = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector2d s = project(cam, p);
    for (size_t i = 0; i < balls.size(); ++i)
      if ((s - balls[i]).norm() < radii[i] + 3.0) return;
    samples.add(forward, marked, s);
  };
  for (double x = 0.06; x <= 0.33; x += 0.004)
    for (double y = -0.18; y <= 0.18; y += 0.004) sample(Eigen::Vector3d(x, y, kTop));
  for (double x = -0.59; x <= -0.11; x += 0.004)
    for (double phi = -0.8; phi <= 0.05; phi += 0.03)
      sample(Eigen::Vector3d(x, kCapR * std::sin(phi), kAxisZ + kCapR * std::cos(phi)));
  ASSERT_GT(samples.diff.size(), 2000u);
  EXPECT_GT(samples.between(0.0, 0.6), 100) << "points in the balls' shadows";
  EXPECT_GT(samples.between(0.6, 0.9), 10) << "points in their penumbrae";
  const double worst = samples.worst();
  EXPECT_LT(worst, 3.0) << "the marked frame differs from the forward one by " << worst << " (0-255 luminance)";
}

TEST(Renderer, SameDrawListIsByteIdentical) {
  REQUIRE_GL();
  auto scene = [](Renderer& r) {
    r.drawSphere(kSphereC, kSphereR, red());
    r.drawTaperedCapsule({0.2, 0.1, 0.3}, {0.3, 0.2, 0.1}, 0.04, 0.02, Material{});
    r.drawBox(Eigen::Translation3d(-0.25, 0.1, 0.05) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()),
              Eigen::Vector3d(0.05, 0.08, 0.05), Material{});
    r.drawLine({0, 0, 0}, {0, 0, 0.5}, {0.1f, 0.3f, 0.9f});
  };
  const auto a = render(testCamera(), testParams(), scene);
  const auto b = render(testCamera(), testParams(), scene);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(a == b) << "two renders of the same draw list differ";
}

// No AA, 4x MSAA, the post-process filter (the default), and draft quality (never anti-aliased).
TEST(Renderer, MsaaOneAndFourSamplesBothWork) {
  REQUIRE_GL();
  auto scene = [](Renderer& r) { r.drawSphere(kSphereC, kSphereR, red()); };
  const auto empty = render(testCamera(), testParams(1, false), [](Renderer&) {});
  const auto one = render(testCamera(), testParams(1, false), scene);
  EXPECT_FALSE(gl().renderer->stats().post_aa);
  RenderParams msaa = testParams(4, false);
  msaa.antialias = AntiAlias::Msaa;
  const auto four = render(testCamera(), msaa, scene);
  EXPECT_EQ(gl().renderer->stats().samples, 4);
  const auto post = render(testCamera(), testParams(4, false), scene);
  EXPECT_EQ(gl().renderer->stats().samples, 1);
  EXPECT_TRUE(gl().renderer->stats().post_aa);
  RenderParams draft = testParams(4, false);
  draft.quality = RenderQuality::Draft;
  const auto drafted = render(testCamera(), draft, scene);
  EXPECT_TRUE(gl().renderer->stats().draft);
  EXPECT_FALSE(gl().renderer->stats().post_aa);
  EXPECT_EQ(gl().renderer->stats().samples, 1);
  save("post.png", post);
  save("draft.png", drafted);
  save("msaa1.png", one);
  save("msaa4.png", four);
  // Both show the sphere with the same area.
  auto coverage = [&](const std::vector<uint8_t>& img) {
    int n = 0;
    for (size_t i = 0; i < img.size(); i += 4)
      n += std::abs(img[i] - empty[i]) + std::abs(img[i + 1] - empty[i + 1]) > 12;
    return n;
  };
  const int c1 = coverage(one), c4 = coverage(four);
  EXPECT_GT(c1, 1000);
  EXPECT_NEAR(double(c4), double(c1), 0.05 * c1);
  // Silhouette pixels (changed, next to an unchanged one): with 1 sample they carry the object's
  // colour (as strong a change as their neighbours'), with 4 they are blends (a weaker change).
  auto blended = [&](const std::vector<uint8_t>& img) {
    auto change = [&](int x, int y) {
      const size_t i = (size_t(y) * kW + size_t(x)) * 4;
      return std::abs(img[i] - empty[i]) + std::abs(img[i + 1] - empty[i + 1]) + std::abs(img[i + 2] - empty[i + 2]);
    };
    int n = 0;
    for (int y = 1; y + 1 < kH; ++y)
      for (int x = 1; x + 1 < kW; ++x) {
        const int c = change(x, y);
        if (c <= 6) continue;
        int strongest = 0, weakest = 1 << 20;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            strongest = std::max(strongest, change(x + dx, y + dy));
            weakest = std::min(weakest, change(x + dx, y + dy));
          }
        if (weakest <= 6 && c < 0.75 * strongest) ++n;
      }
    return n;
  };
  const int b1 = blended(one), b4 = blended(four), bp = blended(post), bd = blended(drafted);
  EXPECT_GT(b4, 1.6 * b1 + 20) << "anti-aliased edge pixels: 1 sample " << b1 << ", 4 samples " << b4;
  EXPECT_GT(bp, 1.6 * b1 + 20) << "anti-aliased edge pixels: 1 sample " << b1 << ", post filter " << bp;
  EXPECT_LT(bd, 1.3 * b1 + 20) << "draft is not anti-aliased: 1 sample " << b1 << ", draft " << bd;
  EXPECT_NEAR(double(coverage(post)), double(c1), 0.05 * c1);
}

TEST(Renderer, TaperedCapsuleChainHasNoGaps) {
  REQUIRE_GL();
  const Camera cam = cameraAt(Eigen::Vector3d(0.0, -1.2, 0.3), Eigen::Vector3d(0.0, 0.0, 0.3));
  const RenderParams rp = testParams(4, false);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> radii;
  for (int i = 0; i <= 12; ++i) {
    const double s = i / 12.0;
    pts.emplace_back(-0.3 + 0.6 * s, 0.0, 0.3 + 0.12 * std::sin(6.0 * s));
    radii.push_back(0.035 * (1.0 - 0.7 * s));
  }
  Material hair;
  hair.color = Eigen::Vector3f(0.35f, 0.2f, 0.1f);
  const auto empty = render(cam, rp, [](Renderer&) {});
  const auto img = render(cam, rp, [&](Renderer& r) {
    for (size_t i = 0; i + 1 < pts.size(); ++i) r.drawTaperedCapsule(pts[i], pts[i + 1], radii[i], radii[i + 1], hair);
  });
  save("chain.png", img);
  // Every pixel along the projected centre line is covered by the chain.
  int gaps = 0, samples = 0;
  for (size_t i = 0; i + 1 < pts.size(); ++i)
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d p = pts[i] + (pts[i + 1] - pts[i]) * (k / 20.0);
      const Eigen::Vector2d q = project(cam, p);
      const size_t j = (size_t(q.y()) * kW + size_t(q.x())) * 4;
      gaps += std::abs(img[j + 1] - empty[j + 1]) < 20;
      ++samples;
    }
  EXPECT_EQ(gaps, 0) << "of " << samples << " samples along the chain";
  // The thin end really is thinner than the thick end (taper honoured): vertical extent.
  auto thickness = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector2d q = project(cam, p);
    int n = 0;
    for (int y = 0; y < kH; ++y) {
      const size_t j = (size_t(y) * kW + size_t(q.x())) * 4;
      n += std::abs(img[j + 1] - empty[j + 1]) > 20;
    }
    return n;
  };
  EXPECT_GT(thickness(pts[1]), 1.8 * thickness(pts[11]));
}

TEST(Renderer, UploadedMeshIsDrawnWithItsTransform) {
  REQUIRE_GL();
  Renderer& r = *gl().renderer;
  const MeshHandle h = r.upload(makeUvSphere(1.0f, 48, 24));
  const Camera cam = testCamera();
  const RenderParams rp = testParams(4, true);
  const auto img = render(cam, rp, [&](Renderer& rr) {
    Eigen::Affine3d T = Eigen::Translation3d(kSphereC) * Eigen::Scaling(kSphereR);
    rr.drawMesh(h, T, red());
  });
  const auto hull = render(cam, rp, [](Renderer& rr) { rr.drawSphere(kSphereC, kSphereR, red()); });
  save("mesh_sphere.png", img);
  // Same sphere through the mesh path and through the instanced hull path: nearly the same image.
  double diff = 0.0;
  for (size_t i = 0; i < img.size(); ++i) diff += std::abs(int(img[i]) - int(hull[i]));
  EXPECT_LT(diff / double(img.size()), 1.0);
  r.release(h);
}

// A mesh's hair region (MeshData::hair) is drawn with the hair's colour and strand highlight where
// it is marked, and the rest of the mesh exactly as without one.
TEST(Renderer, HairRegionIsDrawnAsHairAndTheSkinAsBefore) {
  REQUIRE_GL();
  Renderer& r = *gl().renderer;
  MeshData sphere = makeUvSphere(1.0f, 48, 24);
  const MeshHandle plain = r.upload(sphere);
  for (const Eigen::Vector3f& p : sphere.positions)
    sphere.hair.push_back(std::clamp((p.z() - 0.3f) / 0.1f, 0.0f, 1.0f));
  const MeshHandle marked = r.upload(sphere);
  Material skin;
  skin.color = Eigen::Vector3f(0.93f, 0.78f, 0.67f);
  ScalpHair hair;  // brown, the strands' default highlight, combed towards +z
  const Camera cam = testCamera();
  const RenderParams rp = testParams(1, false);
  const Eigen::Affine3d T(Eigen::Translation3d(kSphereC) * Eigen::Scaling(kSphereR));
  const auto draw = [&](MeshHandle h, const ScalpHair& look) {
    return render(cam, rp, [&](Renderer& rr) { rr.drawMesh(h, T, skin, look); });
  };
  const auto before = draw(plain, hair), after = draw(marked, hair);
  ScalpHair matte = hair;
  matte.shading.highlight = 0.0f;
  const auto dull = draw(marked, matte);
  save("hair_region.png", after);
  // Below the hairline (z < 0.3 R): the same pixels; above it hair: brown, red over blue.
  const Eigen::Vector2d low = project(cam, kSphereC + kSphereR * Eigen::Vector3d(0.3, -0.9, -0.2));
  const Eigen::Vector2d high = project(cam, kSphereC + kSphereR * Eigen::Vector3d(0.2, -0.5, 0.8));
  const auto px = [](const std::vector<uint8_t>& img, const Eigen::Vector2d& at) {
    const uint8_t* p = img.data() + (size_t(at.y()) * kW + size_t(at.x())) * 4;
    return Eigen::Vector3i(p[0], p[1], p[2]);
  };
  EXPECT_EQ(px(before, low), px(after, low));
  EXPECT_GT(px(after, high).x(), px(after, high).z() + 30) << px(after, high).transpose();
  EXPECT_LT(luminance(after, int(high.x()), int(high.y())), luminance(before, int(high.x()), int(high.y())) - 40.0);
  // The highlight knob reaches the hair region: the matte one is darker somewhere above the line.
  double lit = 0.0, matte_lit = 0.0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) lit += luminance(after, x, y), matte_lit += luminance(dull, x, y);
  EXPECT_GT(lit, matte_lit + 500.0);
  r.release(plain);
  r.release(marked);
}

TEST(Camera, OrbitAndFollowPlaceTheEye) {
  CameraParams p;
  p.mode = CameraMode::Orbit;
  p.target = Eigen::Vector3d(0.1, 0.2, 0.3);
  p.orbit_distance = 2.0;
  p.orbit_height = 0.5;
  p.orbit_angle = 0.0;
  p.orbit_speed = 90.0;
  const Camera c = cameraAt(p, 1.0);  // azimuth 90 deg: +y side
  EXPECT_NEAR(c.eye.x(), 0.1, 1e-9);
  EXPECT_NEAR(c.eye.y(), 2.2, 1e-9);
  EXPECT_NEAR(c.eye.z(), 0.8, 1e-9);
  EXPECT_TRUE(c.target.isApprox(p.target));

  p.mode = CameraMode::Follow;
  const Eigen::Vector3d body(1.0, 1.0, 1.0);
  const Camera f = cameraAt(p, 5.0, &body);
  EXPECT_TRUE(f.target.isApprox(body));
  EXPECT_NEAR(f.eye.x(), 3.0, 1e-9);  // azimuth stays orbit_angle in follow mode

  // Smoothed follow: x/y exact, a sudden jump in height is followed gradually.
  FollowCamera fc;
  fc.update(p, 0.0, Eigen::Vector3d(0, 0, 0), 0.0);
  const Camera g = fc.update(p, 1.0 / 30, Eigen::Vector3d(0.5, 0, 1.0), 1.0 / 30);
  EXPECT_NEAR(g.target.x(), 0.5, 1e-12);
  EXPECT_GT(g.target.z(), 0.0);
  EXPECT_LT(g.target.z(), 0.2);
  Camera h = g;
  for (int i = 0; i < 90; ++i) h = fc.update(p, 0.0, Eigen::Vector3d(0.5, 0, 1.0), 1.0 / 30);
  EXPECT_NEAR(h.target.z(), 1.0, 1e-2);

  // View matrix: the target is straight ahead (-z in eye space).
  const Eigen::Vector4d t = c.view() * c.target.homogeneous();
  EXPECT_NEAR(t.x(), 0.0, 1e-9);
  EXPECT_NEAR(t.y(), 0.0, 1e-9);
  EXPECT_LT(t.z(), 0.0);
}

// A demo-like 1280x720 frame: the head mesh (or a 40k-triangle sphere when the asset is absent),
// a tapered ponytail and a hopper. Prints the timings reported in docs/RENDERING.md; asserts only
// that the frame is not empty.
TEST(Renderer, DemoFrame720p) {
  REQUIRE_GL();
  Renderer& r = *gl().renderer;
  MeshData head;
  std::string err;
  HeadParams hp;
  if (!loadMesh("assets/head/head.obj", head, &err)) {
    head = makeUvSphere(0.12f, 200, 100);  // ~40k triangles
    hp.up_axis = UpAxis::Z;
  }
  transformMesh(head, meshToBody(hp, head.bbox));
  const MeshHandle h = r.upload(head);
  RenderParams rp;  // 1280 x 720, 4 samples
  LightParams light;
  const Camera cam = cameraAt(Eigen::Vector3d(0.9, -1.4, 0.55), Eigen::Vector3d(0.0, 0.0, 0.25));
  Material skin, hair, metal, dark;
  skin.color = Eigen::Vector3f(0.93f, 0.78f, 0.67f);
  skin.specular = 0.08f;
  skin.shininess = 20.0f;
  hair.color = Eigen::Vector3f(0.45f, 0.26f, 0.12f);
  hair.specular = 0.3f;
  hair.shininess = 60.0f;
  metal.color = Eigen::Vector3f(0.3f, 0.45f, 0.75f);
  dark.color = Eigen::Vector3f(0.2f, 0.2f, 0.22f);
  auto scene = [&](Renderer& rr) {
    // Head turned to a three-quarter view so that the ponytail (from the bun, back-top) shows.
    const Eigen::Affine3d pose =
        Eigen::Translation3d(0.0, 0.0, 0.35) * Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitZ());
    rr.drawMesh(h, pose, skin);
    Eigen::Vector3d prev = pose * Eigen::Vector3d(0.0, 0.1, 0.09);
    for (int i = 1; i <= 16; ++i) {
      const double s = i / 16.0;
      const Eigen::Vector3d p = pose * Eigen::Vector3d(0.05 * std::sin(4 * s), 0.1 + 0.1 * s, 0.09 - 0.3 * s * s);
      rr.drawTaperedCapsule(prev, p, 0.022 * (1.0 - 0.6 * (s - 1.0 / 16)), 0.022 * (1.0 - 0.6 * s), hair);
      prev = p;
    }
    // Hopper: body box, leg capsule, foot sphere.
    const Eigen::Affine3d body =
        Eigen::Translation3d(0.45, 0.3, 0.45) * Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitY());
    rr.drawBox(body, Eigen::Vector3d(0.08, 0.06, 0.05), metal);
    rr.drawTaperedCapsule(body * Eigen::Vector3d(0, 0, -0.05), body * Eigen::Vector3d(0, 0, -0.38), 0.018, 0.012, dark);
    rr.drawSphere(body * Eigen::Vector3d(0, 0, -0.4), 0.02, dark);
  };
  std::vector<uint8_t> px;
  double total = 0.0, submit = 0.0, readback = 0.0;
  const int n = 3;
  for (int i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    r.beginFrame(cam, light, rp);
    scene(r);
    r.endFrame();
    r.readPixels(px);
    total += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    submit += r.stats().submit_ms;
    readback += r.stats().readback_ms;
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::string werr;
  ASSERT_TRUE(writePngAtomic(outFolder("renderer") + "/demo_720p.png", rp.width, rp.height, px.data(), &werr)) << werr;
  const double encode = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "demo 1280x720, %zu triangles (%zu in the head), %d samples: render %.1f ms/frame (submit %.1f, "
      "readback+finish %.1f), PNG encode %.1f ms; %s / %s\n",
      r.stats().triangles, head.triangleCount(), r.stats().samples, total / n, submit / n, readback / n, encode,
      gl().ctx->rendererName().c_str(), gl().ctx->version().c_str());
  ASSERT_EQ(px.size(), size_t(1280 * 720 * 4));
  r.release(h);
}

// A single-sample frame keeps the half-resolution ground, and the ground upsampled from it, from
// the last frame while the camera and the light stay (render_passes.cpp, groundKey()): it draws
// again only where the last frame's ground shadow was and where this one's is. Each frame of a
// still camera must be the frame a renderer that kept nothing draws (here: the same frame right
// after one from another camera), to the byte: the shadow moved, gone, come back.
TEST(Renderer, TheGroundKeptBetweenFramesIsTheGroundDrawnAnew) {
  REQUIRE_GL();
  const Camera cam = testCamera();
  Camera other = cam;
  other.eye.x() += 0.3;
  const RenderParams rp = testParams(1);
  const auto sphereAt = [](const Eigen::Vector3d& c) { return [c](Renderer& r) { r.drawSphere(c, 0.1, red()); }; };
  const auto nothing = [](Renderer&) {};
  const Eigen::Vector3d a(0.0, 0.0, 0.2), b(0.3, 0.15, 0.25), c(-0.25, -0.1, 0.3);
  render(other, rp, nothing);
  std::vector<std::vector<uint8_t>> kept;
  kept.push_back(render(cam, rp, sphereAt(a)));  // drawn whole
  kept.push_back(render(cam, rp, sphereAt(b)));  // the half-resolution ground kept
  kept.push_back(render(cam, rp, sphereAt(b)));  // the upsampled ground kept too
  kept.push_back(render(cam, rp, sphereAt(c)));
  kept.push_back(render(cam, rp, nothing));
  kept.push_back(render(cam, rp, sphereAt(a)));
  const std::vector<Eigen::Vector3d> at = {a, b, b, c, Eigen::Vector3d::Zero(), a};
  std::vector<uint8_t> lit;
  for (size_t i = 0; i < kept.size(); ++i) {
    render(other, rp, nothing);
    const auto anew = i == 4 ? render(cam, rp, nothing) : render(cam, rp, sphereAt(at[i]));
    if (i == 4) lit = anew;
    ASSERT_EQ(kept[i].size(), anew.size());
    size_t differ = 0;
    for (size_t k = 0; k < anew.size(); ++k) differ += kept[i][k] != anew[k];
    EXPECT_EQ(differ, 0u) << "frame " << i << ": the kept ground differs from the ground drawn anew";
  }
  save("kept_ground_c.png", kept[3]);
  // The frames do show a shadow: outside the sphere's disc (and 3 pixels around it), the frame
  // with the sphere at c differs from the one without it (its shadow on the ground).
  const Eigen::Vector2d centre = project(cam, c);
  const double r_px = (project(cam, c + cam.view().block<1, 3>(1, 0).transpose() * 0.1) - centre).norm();
  int shadow = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      shadow += (Eigen::Vector2d(x, y) - centre).norm() > r_px + 3.0 &&
                std::abs(luminance(kept[3], x, y) - luminance(lit, x, y)) > 3.0;
  EXPECT_GT(shadow, 200) << "no shadow on the ground";
}

// A single-sample frame draws the ground as a grid lit at its corners, with only the checker per
// pixel (and, where the ground's shadow may fall, the shadow and the tone curve): it must look
// like the ground shaded per pixel, as the 4x MSAA frame draws it, in the light, in the
// sphere's shadow and where the ground fades into the background. Pixel for pixel, away from the
// sphere's silhouette (which MSAA smooths another way) and the checker's edges (its filter is
// another box).
TEST(Renderer, TheGridGroundIsTheGroundShadedPerPixel) {
  REQUIRE_GL();
  const Camera cam = cameraAt(Eigen::Vector3d(0.6, -1.6, 0.6), Eigen::Vector3d(0.0, 0.0, 0.15), 40.0);
  const auto sphere = [](Renderer& r) { r.drawSphere(kSphereC, kSphereR, red()); };
  RenderParams grid = testParams(1, true), msaa = testParams(4, true);
  msaa.antialias = AntiAlias::Msaa;
  const auto a = render(cam, grid, sphere), b = render(cam, msaa, sphere);
  const auto plain = render(cam, testParams(1, true), [](Renderer&) {});
  save("grid_ground.png", a);
  save("grid_ground_msaa.png", b);
  // The sphere's pixels (red: the grey ground has none), grown by 3: left out.
  const auto red_at = [](const std::vector<uint8_t>& px, int x, int y) {
    const uint8_t* p = px.data() + (size_t(y) * kW + size_t(x)) * 4;
    return int(p[0]) - int(p[1]) > 12;
  };
  const auto near_sphere = [&](int x, int y) {
    for (int dy = -3; dy <= 3; ++dy)
      for (int dx = -3; dx <= 3; ++dx) {
        const int u = std::clamp(x + dx, 0, kW - 1), v = std::clamp(y + dy, 0, kH - 1);
        if (red_at(a, u, v) || red_at(b, u, v)) return true;
      }
    return false;
  };
  int n = 0, shadowed = 0, far_off = 0;
  double sum = 0.0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      if (near_sphere(x, y)) continue;
      const double d = std::abs(luminance(a, x, y) - luminance(b, x, y));
      sum += d;
      ++n;
      if (d > 6.0) ++far_off;
      if (luminance(plain, x, y) - luminance(a, x, y) > 20.0) ++shadowed;
    }
  std::printf("grid ground: %d pixels compared, mean difference %.3f, %d over 6 levels, %d shadowed\n", n, sum / n,
              far_off, shadowed);
  ASSERT_GT(n, kW * kH / 2);
  EXPECT_GT(shadowed, 200) << "the sphere's shadow is on the grid ground";
  EXPECT_LT(sum / n, 1.0) << "mean luminance difference to the per-pixel ground";
  EXPECT_LT(far_off, n / 100) << "pixels more than 6 levels from the per-pixel ground";
}

// The ground shadow's pixel rectangle (groundShadowRect) is the casters' box in the light's view,
// carried along the light onto the ground and projected. With one caster behind the eye, part of
// that parallelogram is behind the eye too: it is cut at the near plane, and what is left must
// still hold the shadow of the caster in front, near the bottom of the frame (where the cut is),
// at one sample (the grid ground) and four.
TEST(Renderer, AGroundShadowNearTheEyeIsDrawnWhenACasterIsBehindIt) {
  REQUIRE_GL();
  const Camera cam = cameraAt(Eigen::Vector3d(0.0, -1.2, 0.5), Eigen::Vector3d(0.0, 0.5, 0.1), 40.0);
  const Eigen::Vector3d d = LightParams().direction.normalized();
  const Eigen::Vector3d front(0.25, -0.3, 0.2), behind(0.0, -3.0, 0.3);
  const auto onGround = [&](const Eigen::Vector3d& c) { return Eigen::Vector3d(c + d * (c.z() / -d.z())); };
  const Eigen::Vector3d fwd = (cam.target - cam.eye).normalized();
  ASSERT_LT((onGround(behind) - cam.eye).dot(fwd), -0.5) << "the far caster's shadow is behind the eye";
  ASSERT_LT((behind - cam.eye).dot(fwd), -0.5) << "the far caster is behind the eye";
  constexpr double kR = 0.08;
  const auto both = [&](Renderer& r) {
    r.drawSphere(front, kR, red());
    r.drawSphere(behind, kR, red());
  };
  const auto nothing = [](Renderer&) {};
  for (int samples : {1, 4}) {
    const auto shadowed = render(cam, testParams(samples), both);
    const auto lit = render(cam, testParams(samples), nothing);
    save("near_shadow_" + std::to_string(samples) + ".png", shadowed);
    const Eigen::Vector2d c = project(cam, front), p = project(cam, onGround(front));
    const double r_px = (project(cam, front + cam.view().block<1, 3>(1, 0).transpose() * kR) - c).norm();
    ASSERT_GT((p - c).norm(), r_px + 3.0) << "the sphere hides its shadow's centre";
    ASSERT_TRUE(p.x() > 2 && p.y() > kH / 2 && p.x() < kW - 3 && p.y() < kH - 3) << p.transpose();
    const double dl = luminance(lit, int(p.x()), int(p.y())) - luminance(shadowed, int(p.x()), int(p.y()));
    EXPECT_GT(dl, 20.0) << "no shadow near the eye at " << samples << " sample(s), pixel " << p.transpose();
  }
}

TEST(Renderer, AShadowInTheGroundsRingIsDrawn) {
  REQUIRE_GL();
  const Camera cam = testCamera();
  // The fade starts 2 D + 1 m from the point looked at; the square inside it has half that over
  // sqrt(2). The shadow's centre 4 m beyond the point looked at, along the view: in the ring
  // (outside the square, before the fade starts).
  const double D = (cam.target - cam.eye).norm();
  const double fade_start = 2.0 * D + 1.0, inner = fade_start / std::sqrt(2.0);
  Eigen::Vector3d fwd = cam.target - cam.eye;
  fwd.z() = 0.0;
  fwd.normalize();
  const Eigen::Vector3d hit = Eigen::Vector3d(cam.target.x(), cam.target.y(), 0.0) + fwd * 4.0;
  ASSERT_GT(std::max(std::abs(hit.x() - cam.target.x()), std::abs(hit.y() - cam.target.y())), inner + 0.2);
  ASSERT_LT((hit - Eigen::Vector3d(cam.target.x(), cam.target.y(), 0.0)).norm(), fade_start - 0.2);
  const Eigen::Vector3d d = LightParams().direction.normalized();
  const Eigen::Vector3d centre = hit - d * (0.5 / -d.z());  // 0.5 m above the ground, towards the light
  constexpr double kR = 0.15;
  const auto sphere = [&](Renderer& r) { r.drawSphere(centre, kR, red()); };
  const auto nothing = [](Renderer&) {};
  for (int samples : {1, 4}) {
    const auto shadowed = render(cam, testParams(samples), sphere);
    const auto lit = render(cam, testParams(samples), nothing);
    save("ring_shadow_" + std::to_string(samples) + ".png", shadowed);
    const Eigen::Vector2d c = project(cam, centre), p = project(cam, hit);
    const double r_px = (project(cam, centre + cam.view().block<1, 3>(1, 0).transpose() * kR) - c).norm();
    ASSERT_GT((p - c).norm(), r_px + 3.0) << "the sphere hides its shadow's centre";
    ASSERT_TRUE(p.x() > 2 && p.y() > 2 && p.x() < kW - 3 && p.y() < kH - 3);
    const double dl = luminance(lit, int(p.x()), int(p.y())) - luminance(shadowed, int(p.x()), int(p.y()));
    EXPECT_GT(dl, 20.0) << "no shadow in the ring at " << samples << " sample(s), pixel " << p.transpose();
  }
}

// The grid ground looks the shadow up per pixel only inside each caster's own rectangle
// (groundShadowRects: its corners carried along the light onto the ground, grown by the taps'
// reach). A floating plate's shadow has a soft edge outside its corners' shadow; a pole beside it
// makes the box around both rectangles (where the MSAA frame's per-pixel ground looks the shadow
// up) reach past the plate's rectangle. The two frames' ground must agree around the plate's
// shadow (92 pixels over 6 levels when the rectangles are not grown by the reach), and both
// shadows must be on the grid ground.
TEST(Renderer, EachCastersShadowOnTheGridGroundKeepsItsSoftEdge) {
  REQUIRE_GL();
  const Eigen::Vector3d d = LightParams().direction.normalized();
  const Eigen::Vector3d box_c(-0.25, 0.1, 0.9), pole0(-0.25, 0.3, 0.0), pole1(-0.25, 0.3, 0.7);
  const Eigen::Vector3d target(-0.65, 0.6, 0.0);
  const Camera cam = cameraAt(target + Eigen::Vector3d(0.3, -0.8, 0.5), target, 40.0);
  // A thin square plate turned so that its shadow's near and far edges run along the rows: the
  // bound of its rectangle lies on them, and the soft edge is outside it along their length.
  const Eigen::Vector3d half(0.08, 0.08, 0.01);
  const Eigen::Vector3d right = (cam.target - cam.eye).cross(Eigen::Vector3d::UnitZ());
  const Eigen::Affine3d plate =
      Eigen::Translation3d(box_c) * Eigen::AngleAxisd(std::atan2(right.y(), right.x()), Eigen::Vector3d::UnitZ());
  const auto onGround = [&](const Eigen::Vector3d& c) { return Eigen::Vector3d(c + d * (c.z() / -d.z())); };
  const auto scene = [&](Renderer& r) {
    r.drawBox(plate, half, red());
    r.drawCapsule(pole0, pole1, 0.015, red());
  };
  RenderParams grid = testParams(1, true), msaa = testParams(4, true);
  msaa.antialias = AntiAlias::Msaa;
  const auto a = render(cam, grid, scene), b = render(cam, msaa, scene);
  const auto plain = render(cam, grid, [](Renderer&) {});
  save("caster_rects_grid.png", a);
  save("caster_rects_msaa.png", b);
  const Eigen::Vector2d box_px = project(cam, box_c), shadow_px = project(cam, onGround(box_c));
  const Eigen::Vector2d pole_px = project(cam, onGround(0.5 * (pole0 + pole1)));
  for (const Eigen::Vector2d& p : {shadow_px, pole_px})
    ASSERT_TRUE(p.x() > 20 && p.y() > 20 && p.x() < kW - 20 && p.y() < kH - 20) << p.transpose();
  EXPECT_GT(
      luminance(plain, int(shadow_px.x()), int(shadow_px.y())) - luminance(a, int(shadow_px.x()), int(shadow_px.y())),
      20.0)
      << "the plate's shadow on the grid ground";
  EXPECT_GT(luminance(plain, int(pole_px.x()), int(pole_px.y())) - luminance(a, int(pole_px.x()), int(pole_px.y())),
            20.0)
      << "the pole's shadow on the grid ground";
  // Around the plate's shadow (its ground pixels: none red, 40 pixels of it from its centre, away
  // from the plate itself), the grid ground against the per-pixel ground.
  const auto red_at = [](const std::vector<uint8_t>& px, int x, int y) {
    const uint8_t* p = px.data() + (size_t(y) * kW + size_t(x)) * 4;
    return int(p[0]) - int(p[1]) > 12;
  };
  int n = 0, far_off = 0;
  double worst = 0.0;
  for (int y = std::max(0, int(shadow_px.y()) - 40); y < std::min(kH, int(shadow_px.y()) + 40); ++y)
    for (int x = std::max(0, int(shadow_px.x()) - 40); x < std::min(kW, int(shadow_px.x()) + 40); ++x) {
      if ((Eigen::Vector2d(x, y) - box_px).norm() < 30.0 || red_at(a, x, y) || red_at(b, x, y)) continue;
      const double diff = std::abs(luminance(a, x, y) - luminance(b, x, y));
      worst = std::max(worst, diff);
      ++n;
      if (diff > 6.0) ++far_off;
    }
  std::printf("around the plate's shadow: %d pixels, %d over 6 levels, worst %.1f\n", n, far_off, worst);
  ASSERT_GT(n, 2000);
  EXPECT_LE(far_off, 3) << "the grid ground's shadow of the box is cut short of its soft edge";
}

// The post filter runs on a box only in bands along the lines where its picture can jump (its
// edges, where it meets the ground, where it cuts into another box) and where another draw's
// shadow can fall on it (postFilterRegions). Against the filter over the whole frame (a debug line
// behind the eye leaves the frame unbounded): the same pixels around the boxes. Part 1, no key
// light: a slab sunk into the ground at a slant and a box cutting into it at a skew; part 2, with
// shadows: a sphere just above a slab, its shadow on the slab's top.
TEST(Renderer, ThePostFilterFiltersEveryEdgeOfABox) {
  REQUIRE_GL();
  const Camera cam = cameraAt(Eigen::Vector3d(0.6, -1.1, 0.7), Eigen::Vector3d(0.0, 0.05, 0.0), 40.0);
  const Eigen::Vector3d back = cam.eye + (cam.eye - cam.target).normalized();
  const auto whole = [&](Renderer& r) { r.drawLine(back, back + Eigen::Vector3d(0.0, 0.0, 0.1), {1.0f, 0.0f, 0.0f}); };
  Material dark = red(), yellow;
  dark.color = Eigen::Vector3f(0.35f, 0.12f, 0.1f);
  yellow.color = Eigen::Vector3f(0.95f, 0.85f, 0.3f);
  const Eigen::Affine3d slab = Eigen::Translation3d(0.0, 0.0, 0.01) * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitX());
  const Eigen::Affine3d cutter = Eigen::Translation3d(0.05, 0.05, 0.06) *
                                 Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY());
  const Eigen::Vector3d slab_half(0.25, 0.18, 0.05), cutter_half(0.05, 0.05, 0.09);
  const auto boxes = [&](Renderer& r) {
    r.drawBox(slab, slab_half, dark);
    r.drawBox(cutter, cutter_half, yellow);
  };
  // The pixels (x right, y down) around the boxes: their corners' box, grown by 8 px.
  const auto around = [&](const std::vector<Eigen::Affine3d>& poses, const std::vector<Eigen::Vector3d>& halves) {
    Eigen::AlignedBox2d b;
    for (size_t k = 0; k < poses.size(); ++k)
      for (int i = 0; i < 8; ++i)
        b.extend(project(cam, poses[k] * Eigen::Vector3d(i & 1 ? halves[k].x() : -halves[k].x(),
                                                         i & 2 ? halves[k].y() : -halves[k].y(),
                                                         i & 4 ? halves[k].z() : -halves[k].z())));
    b.min().array() -= 8.0;
    b.max().array() += 8.0;
    return b;
  };
  // Pixels of `a` and `b` that differ inside `box` (and where `keep` says), and of `a` and `raw`.
  const auto count = [](const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, const Eigen::AlignedBox2d& box,
                        const std::function<bool(int, int)>& keep) {
    int n = 0;
    for (int y = std::max(0, int(box.min().y())); y < std::min(kH, int(box.max().y()) + 1); ++y)
      for (int x = std::max(0, int(box.min().x())); x < std::min(kW, int(box.max().x()) + 1); ++x) {
        const size_t i = (size_t(y) * kW + size_t(x)) * 4;
        if (keep(x, y) && !std::equal(a.begin() + std::ptrdiff_t(i), a.begin() + std::ptrdiff_t(i + 4),
                                      b.begin() + std::ptrdiff_t(i)))
          ++n;
      }
    return n;
  };
  const auto all = [](int, int) { return true; };
  {
    LightParams unlit = testLight();
    unlit.intensity = 0.0;
    const auto banded = render(cam, testParams(), boxes, unlit);
    const auto full = render(
        cam, testParams(), [&](Renderer& r) { boxes(r), whole(r); }, unlit);
    const auto raw = render(cam, testParams(1), boxes, unlit);
    save("post_boxes.png", banded);
    const Eigen::AlignedBox2d box = around({slab, cutter}, {slab_half, cutter_half});
    const int filtered = count(full, raw, box, all), missed = count(banded, full, box, all);
    std::printf("boxes: %d pixels filtered over the whole frame, %d of them missed\n", filtered, missed);
    EXPECT_GT(filtered, 300);
    EXPECT_EQ(missed, 0) << "an edge of a box left unfiltered";
  }
  {
    const Eigen::Affine3d top = Eigen::Translation3d(0.0, 0.1, 0.04) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d top_half(0.3, 0.22, 0.04), ball(0.1, 0.0, 0.3);
    const auto scene = [&](Renderer& r) {
      r.drawBox(top, top_half, Material{});
      r.drawSphere(ball, 0.04, red());
    };
    const auto banded = render(cam, testParams(), scene);
    const auto full = render(cam, testParams(), [&](Renderer& r) { scene(r), whole(r); });
    const auto raw = render(cam, testParams(1), scene);
    save("post_box_shadow.png", banded);
    // The slab's top face 10 px inside its outline (none of its own edges, nor its shadow on the
    // ground), away from the sphere's own rectangle (26 px from its centre).
    std::array<Eigen::Vector2d, 4> c;
    for (int i = 0; i < 4; ++i)
      c[size_t(i)] = project(cam, top * Eigen::Vector3d((i == 1 || i == 2) ? top_half.x() : -top_half.x(),
                                                        i >= 2 ? top_half.y() : -top_half.y(), top_half.z()));
    const Eigen::Vector2d ball_px = project(cam, ball);
    const auto inside = [&](int x, int y) {
      const Eigen::Vector2d p(x, y);
      if ((p - ball_px).norm() < 26.0) return false;
      double sign = 0.0;
      for (int i = 0; i < 4; ++i) {
        const Eigen::Vector2d a = c[size_t(i)], b = c[size_t((i + 1) % 4)], e = (b - a).normalized();
        const double d = e.x() * (p - a).y() - e.y() * (p - a).x();  // signed distance to the side
        if (sign == 0.0) sign = d > 0 ? 1.0 : -1.0;
        if (d * sign < 10.0) return false;
      }
      return true;
    };
    const Eigen::AlignedBox2d box = around({top}, {top_half});
    const int filtered = count(full, raw, box, inside), missed = count(banded, full, box, inside);
    std::printf("a sphere's shadow on a box: %d pixels filtered over the whole frame, %d of them missed\n", filtered,
                missed);
    EXPECT_GT(filtered, 20);
    EXPECT_EQ(missed, 0) << "the edge of a shadow on a box left unfiltered";
  }
}

// The still draws' shadows kept between frames (Renderer::drawMesh's `still`; shadowMapPass,
// groundShadowPass): a frame that keeps them must be the frame drawn anew, pixel for pixel. A
// moving sphere moves over still boxes (its last depth and its last shadow on the ground must go);
// then the key must see an edit of a still box (under fixed shadow bounds, so that the light's
// frustum stays the same), a turned light and another map size: each of those frames is drawn
// anew. "Anew": after a frame without still draws, which keeps nothing.
TEST(Renderer, TheStillShadowsKeptBetweenFramesAreTheShadowsDrawnAnew) {
  REQUIRE_GL();
  Renderer& r = *gl().renderer;
  const Camera cam = testCamera();
  const RenderParams rp = testParams(1);
  struct Frame {
    Eigen::Vector3d sphere;
    double post_x = 0.0;  // the still post moved along x
    LightParams light;
    bool bounds = false;  // fixed shadow bounds
    bool kept = false;    // expected: the still shadows kept from the frame before
  };
  const auto scene = [](const Frame& f) {
    return [f](Renderer& rr) {
      if (f.bounds)
        rr.setShadowBounds(Eigen::AlignedBox3d(Eigen::Vector3d(-0.6, -0.6, 0.0), Eigen::Vector3d(0.6, 0.6, 0.7)));
      rr.drawBox(Eigen::Affine3d(Eigen::Translation3d(-0.2, 0.1, 0.02)), Eigen::Vector3d(0.25, 0.25, 0.02), red(),
                 true);
      rr.drawBox(Eigen::Affine3d(Eigen::Translation3d(0.5 + f.post_x, 0.3, 0.3)), Eigen::Vector3d(0.04, 0.04, 0.3),
                 red(), true);
      rr.drawSphere(f.sphere, 0.08, red());
    };
  };
  LightParams base = testLight();
  base.shadow_match = false;
  LightParams smaller = base;
  smaller.shadow_size = 512;
  LightParams turned = smaller;
  turned.direction = Eigen::Vector3d(-0.45, 0.6, -1.0);
  // a over the slab, b and c beside it (their shadows on the ground).
  const Eigen::Vector3d a(-0.15, 0.1, 0.2), b(0.2, -0.1, 0.2), c(0.25, -0.15, 0.22);
  const std::vector<Frame> frames = {
      {b, 0.0, base, false, false},   {c, 0.0, base, false, true},     {b, 0.0, base, false, true},
      {b, 0.0, base, true, false},    {a, 0.0, base, true, true},      {a, 0.01, base, true, false},
      {c, 0.01, base, true, true},    {c, 0.01, smaller, true, false}, {a, 0.01, smaller, true, true},
      {a, 0.01, turned, true, false},
  };
  const auto onlySphere = [](Renderer& rr) { rr.drawSphere(Eigen::Vector3d(0.0, 0.0, 0.2), 0.08, red()); };
  std::vector<std::vector<uint8_t>> kept;
  std::vector<bool> was_kept;
  render(cam, rp, onlySphere, base);
  for (const Frame& f : frames) {
    kept.push_back(render(cam, rp, scene(f), f.light));
    was_kept.push_back(r.stats().shadow_kept);
  }
  for (size_t i = 0; i < frames.size(); ++i) {
    render(cam, rp, onlySphere, frames[i].light);
    const auto anew = render(cam, rp, scene(frames[i]), frames[i].light);
    EXPECT_FALSE(r.stats().shadow_kept);
    EXPECT_EQ(was_kept[i], frames[i].kept) << "frame " << i;
    ASSERT_EQ(kept[i].size(), anew.size());
    size_t differ = 0;
    for (size_t k = 0; k < anew.size(); ++k) differ += kept[i][k] != anew[k];
    EXPECT_EQ(differ, 0u) << "frame " << i << ": the kept shadows differ from the shadows drawn anew";
  }
  save("still_kept_c.png", kept[1]);
  save("still_kept_a.png", kept[4]);
}

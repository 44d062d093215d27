// The window of `ponyhop run`: GLFW + the same Renderer as the headless path + the tuning panel.
// GL is loaded through glfwGetProcAddress (never -lGL, see engine/gl_context.h). Each frame:
// events -> panel (edits, playback: the physics steps at its own dt up to the new simulated
// time, within a wall-time budget) -> scene render -> compose (scene blit + ImGui) -> present. The
// run prints each stage's mean per quality, the compose split into the scene's copy, the panel,
// the present. The savings (docs/bench/render.md, sessions 27 and 28): a still final view whose
// inputs did not change is re-presented, not rendered again (ViewReuse); the panel's running
// figures are refreshed 4 times a second (Panel::setReadoutRefresh); and where the GLX has
// GLX_MESA_copy_sub_buffer (WindowPresenter) the back buffer keeps the frame, only what changed is
// drawn into it (the view's columns, the panel's) and only those rectangles are pushed to the
// screen, nothing at all when nothing changed, and the next frame waits for an event (idle_wait).
// Without the extension the panel is drawn into its own texture only when it changed and copied,
// the frame swapped whole when anything changed (UiGl's panel cache).
#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "app/panel.h"
#include "app/ui_gl.h"
#include "app/ui_headless.h"
#include "app/ui_sim.h"
#include "app/ui_window.h"
#include "app/window_present.h"
#include "engine/frame_writer.h"
#include "engine/gl_context.h"
#include "engine/renderer.h"
#include "physics/stage_times.h"

namespace ponyhop {
namespace {

void glfwError(int code, const char* what) { std::fprintf(stderr, "ponyhop run: GLFW error %d: %s\n", code, what); }

// The panel keeps ~400 px; a narrow window gives it at most 60 % of its width.
PanelLayout layoutFor(int w, int h) {
  PanelLayout l;
  l.width = std::max(w, 1);
  l.height = std::max(h, 1);
  l.panel_width = std::min(Panel::kDefaultWidth, int(0.6 * l.width));
  return l;
}

// ImGui 1.86 reads the keys as one down-state per frame: a tap whose press and release both arrive
// between two frames is never seen as pressed (every tap at a few frames a second, every synthetic
// key of xdotool). Releases of keys pressed since the last frame wait for the next one, as ImGui
// 1.87's input queue does; everything else goes straight to the backend.
struct KeyTrickle {
  std::vector<int> pressed;  // keys pressed since the frame began
  struct Release {
    int key, scancode, mods;
  };
  std::vector<Release> deferred;
  GLFWwindow* window = nullptr;

  // Before glfwPollEvents: the releases held back from the last frame.
  void nextFrame() {
    for (const Release& r : deferred) ImGui_ImplGlfw_KeyCallback(window, r.key, r.scancode, GLFW_RELEASE, r.mods);
    deferred.clear();
    pressed.clear();
  }
};
KeyTrickle g_keys;
bool g_exposed = false;  // the window asked to be drawn again (an expose): its pixels are lost

void exposed(GLFWwindow*) { g_exposed = true; }

void trickleKey(GLFWwindow* window, int key, int scancode, int action, int mods) {
  if (action == GLFW_RELEASE && std::find(g_keys.pressed.begin(), g_keys.pressed.end(), key) != g_keys.pressed.end()) {
    g_keys.deferred.push_back({key, scancode, mods});
    return;
  }
  if (action == GLFW_PRESS) g_keys.pressed.push_back(key);
  ImGui_ImplGlfw_KeyCallback(window, key, scancode, action, mods);
}

bool screenshot(const std::string& path, int w, int h) {
  std::vector<uint8_t> rgba(size_t(w) * size_t(h) * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  const size_t row = size_t(w) * 4;
  std::vector<uint8_t> flipped(rgba.size());
  for (int y = 0; y < h; ++y) std::copy_n(rgba.data() + size_t(h - 1 - y) * row, row, flipped.data() + size_t(y) * row);
  for (size_t i = 3; i < flipped.size(); i += 4) flipped[i] = 255;  // the window's alpha means nothing
  std::string err;
  if (!writePngAtomic(path, w, h, flipped.data(), &err)) {
    std::fprintf(stderr, "ponyhop run: screenshot: %s\n", err.c_str());
    return false;
  }
  std::fprintf(stderr, "run: screenshot %s (%dx%d)\n", path.c_str(), w, h);
  return true;
}

// The stage times of the frames of one kind (every frame, or one quality), summed.
struct StageSums {
  std::vector<double> frame_ms;
  double physics = 0, panel = 0, render = 0, compose = 0;
  double copy = 0, panel_draw = 0, swap = 0;       // compose = copy + panel_draw + swap
  int rendered = 0, panel_drawn = 0;               // frames whose scene was rendered, whose panel ImGui drew
  int unchanged = 0;                               // frames that drew and presented nothing
  double unchanged_ms = 0;                         // their frame times
  double panel_drawn_ms = 0, panel_copied_ms = 0;  // the panel's time on those frames and on the others
  double panel_redraw = 0;                         // of panel_drawn_ms: ImGui into the panel's texture
  double rendered_ms = 0, reused_ms = 0;           // their frame times, and those of the re-presented ones
  void add(double frame, double physics_ms, double panel_ms, double render_ms, double compose_ms, const UiGl::Times& ct,
           double swap_ms, bool scene_rendered, bool nothing_changed) {
    frame_ms.push_back(frame);
    unchanged += nothing_changed;
    if (nothing_changed) unchanged_ms += frame;
    rendered += scene_rendered;
    panel_drawn += ct.panel_drawn;
    (ct.panel_drawn ? panel_drawn_ms : panel_copied_ms) += ct.panel_ms;
    panel_redraw += ct.panel_redraw_ms;
    (scene_rendered ? rendered_ms : reused_ms) += frame;
    physics += physics_ms;
    panel += panel_ms;
    render += render_ms;
    compose += compose_ms;
    copy += ct.copy_ms;
    panel_draw += ct.panel_ms;
    swap += swap_ms;
  }
  double mean() const {
    double sum = 0;
    for (double x : frame_ms) sum += x;
    return frame_ms.empty() ? 0.0 : sum / double(frame_ms.size());
  }
};

struct FrameStats {
  StageSums all;
  StageSums draft, final;  // the same frames split by the view's quality
  // Each time the motion stopped (a draft frame followed by a final one): was that first still
  // frame a final picture rendered anew, and how long it took (ms; it is shown at its swap).
  int stops = 0, stops_final_at_once = 0;
  double first_still_ms = 0;
  std::vector<double> each_first_still_ms;
  double waited_ms = 0;  // waiting for events after frames that changed nothing
  int waits = 0;
};

}  // namespace

int runWindow(const Scene& scene, const WindowOptions& o) {
  glfwSetErrorCallback(glfwError);
  if (!glfwInit()) {
    std::fprintf(stderr, "ponyhop run: cannot open a window (no display? headless: xvfb-run -a ponyhop run ...)\n");
    return 1;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  const std::string title = "ponyhop - " + (scene.name.empty() ? scene.path : scene.name);
  GLFWwindow* window = glfwCreateWindow(o.width, o.height, title.c_str(), nullptr, nullptr);
  if (!window) {
    std::fprintf(stderr, "ponyhop run: cannot create a GL 3.3 core window\n");
    glfwTerminate();
    return 1;
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(o.vsync ? 1 : 0);
  int code = 0;
  FILE* quality_log = nullptr;
  if (!o.quality_log.empty() && !(quality_log = std::fopen(o.quality_log.c_str(), "w"))) {
    std::fprintf(stderr, "ponyhop run: --quality-log %s: cannot write\n", o.quality_log.c_str());
    glfwDestroyWindow(window);
    glfwTerminate();
    return 1;
  }
  {
    std::string err;
    if (!loadGL(glfwGetProcAddress, &err)) {
      std::fprintf(stderr, "ponyhop run: %s\n", err.c_str());
      glfwDestroyWindow(window);
      glfwTerminate();
      return 1;
    }
    LiveSim sim(scene);
    sim.setStepBudgetMs(25.0);  // a slow step never freezes the window: the rest is dropped, shown as "behind"
    PanelContext imgui;
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    g_keys = KeyTrickle{};
    g_keys.window = window;
    glfwSetKeyCallback(window, trickleKey);  // in place of the backend's, which trickleKey calls
    glfwSetWindowRefreshCallback(window, exposed);
    g_exposed = false;
    {
      const WindowPresenter presenter(window, o.copy_rects);
      const double idle_wait = o.idle_wait;
      std::fprintf(stderr, "run: frames are presented %s\n", presenter.how());
      UiGl gl;
      gl.setPanelCache(true);
      gl.setTargetKeeps(presenter.copiesRects());
      ViewReuse reuse;
      Renderer renderer;
      if (!renderer.init(&err)) {
        std::fprintf(stderr, "ponyhop run: renderer: %s\n", err.c_str());
        code = 1;
      }
      Panel panel(sim);
      panel.setReadoutRefresh(0.25);
      FrameStats stats;
      int frame = 0;
      bool last_draft = false;
      bool last_unchanged = false;
      while (code == 0 && !glfwWindowShouldClose(window)) {
        auto t_frame = Clock::now();
        const bool releases_waiting = !g_keys.deferred.empty();
        g_keys.nextFrame();
        // Nothing changed on the last frame: ImGui has settled and nothing moves, so wait for the
        // user instead of composing the same frame again (a release held back is shown at once).
        // The wait is not the frame's time.
        if (last_unchanged && idle_wait > 0.0 && !releases_waiting) {
          glfwWaitEventsTimeout(idle_wait);
          stats.waited_ms += msSince(t_frame);
          ++stats.waits;
          t_frame = Clock::now();
        } else {
          glfwPollEvents();
        }
        int win_w = 0, win_h = 0, fb_w = 0, fb_h = 0;
        glfwGetWindowSize(window, &win_w, &win_h);
        glfwGetFramebufferSize(window, &fb_w, &fb_h);
        if (glfwGetWindowAttrib(window, GLFW_ICONIFIED) || fb_w <= 0 || fb_h <= 0 || win_w <= 0 || win_h <= 0) {
          glfwWaitEventsTimeout(0.1);  // minimized: nothing to draw; time does not pile up (advance clamps)
          continue;
        }
        const PanelLayout layout = layoutFor(win_w, win_h);
        const double sx = double(fb_w) / win_w;
        const int scene_fb_w = std::max(1, int(layout.sceneWidth() * sx));

        auto t0 = Clock::now();
        gl.newFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        panel.build(layout);  // edits, playback (physics), mouse
        const RenderQuality quality = viewQuality(sim);
        if (quality_log) {
          const ImGuiIO& io = ImGui::GetIO();
          std::fprintf(quality_log, "frame %d %s running=%d item_active=%d mouse_down=%d", frame,
                       quality == RenderQuality::Draft ? "draft" : "final", sim.running() ? 1 : 0,
                       ImGui::IsAnyItemActive() ? 1 : 0,
                       (io.MouseDown[0] || io.MouseDown[1] || io.MouseDown[2]) ? 1 : 0);
        }
        ImGui::Render();
        const double build_ms = msSince(t0);

        t0 = Clock::now();
        const bool rendered = reuse.render(renderer, sim, panel.camera(), scene_fb_w, fb_h, quality, o.draft_scale);
        const double render_ms = msSince(t0);
        panel.setRenderMs(render_ms);
        if (quality_log)  // the size the view was rendered at (a draft one is upscaled)
          std::fprintf(quality_log, " view=%dx%d of %dx%d", renderer.width(), renderer.height(), scene_fb_w, fb_h);

        t0 = Clock::now();
        UiGl::Times compose_times;
        const bool last = o.frames > 0 && frame + 1 >= o.frames;
        // A swapped back buffer is not kept: the screenshot's frame is drawn whole.
        if (g_exposed || (last && !o.screenshot.empty() && !presenter.copiesRects())) gl.forgetTarget();
        g_exposed = false;
        const UiGl::Damage damage = gl.compose(renderer, 0, fb_w, fb_h, scene_fb_w, &compose_times, rendered);
        if (last && !o.screenshot.empty() && !screenshot(o.screenshot, fb_w, fb_h)) code = 1;
        const auto t_swap = Clock::now();
        // The back buffer to the X server (llvmpipe: a put-image): the rectangles that changed,
        // or the whole frame by a swap; nothing when nothing changed.
        const char* pushed = "none";
        if (presenter.copiesRects()) {
          if (damage.view && damage.panel) {
            presenter.copyRect(0, 0, fb_w, fb_h);
            pushed = "all";
          } else if (damage.view) {
            presenter.copyRect(0, 0, scene_fb_w, fb_h);
            pushed = "view";
          } else if (damage.panel) {
            presenter.copyRect(scene_fb_w, 0, fb_w - scene_fb_w, fb_h);
            pushed = "panel";
          }
        } else if (damage.any()) {
          presenter.swap();
          pushed = "all";
        }
        const double swap_ms = msSince(t_swap);
        const double compose_ms = msSince(t0);
        last_unchanged = !damage.any();

        const double frame_ms = msSince(t_frame);
        panel.setFrameMs(compose_ms, frame_ms);
        if (quality_log) {  // the scene rendered anew or re-presented; the panel drawn by ImGui or copied
          std::fprintf(quality_log, " rendered=%d panel_drawn=%d pushed=%s\n", rendered ? 1 : 0,
                       compose_times.panel_drawn ? 1 : 0, pushed);
          std::fflush(quality_log);
        }
        const bool draft = quality == RenderQuality::Draft;
        if (last_draft && !draft) {  // the motion stopped: this is the first still frame
          ++stats.stops;
          stats.stops_final_at_once += rendered;
          stats.first_still_ms += frame_ms;
          stats.each_first_still_ms.push_back(frame_ms);
        }
        last_draft = draft;
        if (frame >= 5) {  // warm-up frames (font texture, shaders, first shadow map) are not typical
          // This frame's own physics time (the smoothed readout lags: the panel's share came out negative).
          const double physics_ms = sim.readouts().physics_frame_ms;
          for (StageSums* s : {&stats.all, draft ? &stats.draft : &stats.final})
            s->add(frame_ms, physics_ms, build_ms - physics_ms, render_ms, compose_ms, compose_times, swap_ms, rendered,
                   !damage.any());
        }
        ++frame;
        if (last) break;
      }
      if (const size_t n = stats.all.frame_ms.size(); n > 0) {
        std::vector<double> v = stats.all.frame_ms;
        std::sort(v.begin(), v.end());
        const double mean = stats.all.mean();
        int w = 0, h = 0;
        glfwGetFramebufferSize(window, &w, &h);
        std::fprintf(stderr,
                     "run: %zu frames at %dx%d: frame time mean %.1f ms (median %.1f, p95 %.1f) = %.1f fps; "
                     "physics %.2f, panel %.2f, scene render %.2f, compose+swap %.2f ms\n",
                     n, w, h, mean, v[n / 2], v[std::min(n - 1, n * 95 / 100)], 1000.0 / mean, stats.all.physics / n,
                     stats.all.panel / n, stats.all.render / n, stats.all.compose / n);
      }
      for (const auto& [name, s] :
           {std::pair<const char*, const StageSums&>{"draft (moving)", stats.draft}, {"final (still)", stats.final}}) {
        if (s.frame_ms.empty()) continue;
        const double n = double(s.frame_ms.size());
        std::fprintf(stderr,
                     "run: %zu %s frames: mean %.1f ms = %.1f fps (scene render %.2f, compose+swap %.2f ms: "
                     "clear + scene copy %.2f, panel %.2f, swap %.2f)\n",
                     s.frame_ms.size(), name, s.mean(), 1000.0 / s.mean(), s.render / n, s.compose / n, s.copy / n,
                     s.panel_draw / n, s.swap / n);
        const int reused = int(s.frame_ms.size()) - s.rendered;
        std::fprintf(
            stderr,
            "run:   of which %d rendered (mean %.1f ms) and %d re-presented unchanged (mean %.1f ms); "
            "the panel drawn on %d (panel %.2f ms, of which ImGui into %s %.2f), "
            "%s on %d (panel %.2f ms: %s the view's overlay)\n",
            s.rendered, s.rendered ? s.rendered_ms / s.rendered : 0.0, reused, reused ? s.reused_ms / reused : 0.0,
            s.panel_drawn, s.panel_drawn ? s.panel_drawn_ms / s.panel_drawn : 0.0,
            presenter.copiesRects() ? "the frame" : "its texture", s.panel_drawn ? s.panel_redraw / s.panel_drawn : 0.0,
            presenter.copiesRects() ? "left as it was" : "copied", int(s.frame_ms.size()) - s.panel_drawn,
            s.frame_ms.size() > size_t(s.panel_drawn)
                ? s.panel_copied_ms / double(s.frame_ms.size() - size_t(s.panel_drawn))
                : 0.0,
            presenter.copiesRects() ? "when the view changed," : "its columns' copy and");
        if (presenter.copiesRects() || s.unchanged > 0)
          std::fprintf(stderr,
                       "run:   %d frames changed nothing on the screen: nothing drawn or presented (mean %.1f ms)\n",
                       s.unchanged, s.unchanged ? s.unchanged_ms / s.unchanged : 0.0);
      }
      if (stats.waits > 0)
        std::fprintf(stderr, "run: %d frames waited for an event after a frame that changed nothing: %.0f ms in all\n",
                     stats.waits, stats.waited_ms);
      if (stats.stops > 0) {
        std::fprintf(stderr,
                     "run: the motion stopped %d times; the first still frame was a final picture rendered anew "
                     "%d of %d times, shown %.1f ms (mean) after the last moving frame (each:",
                     stats.stops, stats.stops_final_at_once, stats.stops, stats.first_still_ms / stats.stops);
        for (double ms : stats.each_first_still_ms) std::fprintf(stderr, " %.1f", ms);
        std::fprintf(stderr, " ms)\n");
      }
      if (!sim.ok()) std::fprintf(stderr, "run: the simulation stopped: %s\n", sim.stopMessage().c_str());
    }  // GL objects go while the context is current
    ImGui_ImplGlfw_Shutdown();
  }
  if (quality_log) std::fclose(quality_log);
  glfwDestroyWindow(window);
  glfwTerminate();
  return code;
}

}  // namespace ponyhop

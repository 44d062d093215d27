// `ponyhop bench-render [--scenes A.json,B.json] [--sizes 1280x720,1920x1080] [--frames N] [--out FILE.md]`:
// where a frame's render time goes, per pass, for the demo scenes in each configuration of issue 14
// (final quality, then peeling off anti-aliasing, the shadow and the ground down to the bare floor),
// plus the old 4x MSAA and the draft quality. Writes a Markdown table (and prints it).
//
// Each configuration renders `frames` frames of the scene's own motion (the simulation steps to each
// frame's time first; simulation time is not counted) after 2 warm-up frames (shader compilation,
// first target allocation). The configurations take turns frame by frame (one session each), so a
// change in the machine's load falls on all of them alike, and each figure is the median over its
// frames. The render column is the wall time of RenderSession::renderFrame (all passes + the
// read-back), its context made current before the clock starts: switching OSMesa contexts costs
// 0.6-1.4 ms, which bench-render pays at every turn and a single `ponyhop render` never does
// (added to the final frame and the floor alike, it pulled every ratio towards 1); the pass columns are RenderStats
// (glFinish-bracketed on llvmpipe). `--set` applies the same overrides to every configuration (another shadow map size,
// another scene's look).
#include <sys/utsname.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include "app/commands.h"
#include "bench/bench_report.h"
#include "bench/commands.h"
#include "engine/render_session.h"
#include "physics/stage_times.h"
#include "sim/scene_io.h"

namespace ponyhop {

// PONYHOP_DEMO_SCENES is the Makefile's DEMO_SCENES, read at configure time (bench/CMakeLists.txt).
std::vector<std::string> benchRenderDefaultScenes() {
  std::vector<std::string> scenes;
  std::istringstream names(PONYHOP_DEMO_SCENES);
  for (std::string name; names >> name;) scenes.push_back("assets/scenes/" + name + ".json");
  scenes.push_back("assets/scenes/ponytail_hopper.json");
  return scenes;
}

namespace {

struct BenchRenderArgs {
  std::vector<std::string> scenes = benchRenderDefaultScenes();
  std::vector<std::string> sizes{"1280x720", "1920x1080"};
  int frames = 20;
  std::vector<std::string> sets;  // applied to every configuration, before its own
  std::string out = "docs/bench/render_table.md";
};

struct Variant {
  const char* name;
  std::vector<std::string> sets;
};

// The four rows, then the alternatives worth seeing beside them.
const std::vector<Variant>& variants() {
  static const std::vector<Variant> v = {
      {"final (as shipped)", {}},
      {"samples=1 (no AA)", {"render.samples=1"}},
      {"+ light.intensity=0 (no shadow)", {"render.samples=1", "light.intensity=0"}},
      {"+ ground=false: **floor**", {"render.samples=1", "light.intensity=0", "render.ground=false"}},
      {"final with 4x MSAA (antialias=msaa)", {"render.antialias=msaa"}},
      {"draft (quality=draft)", {"render.quality=draft"}},
  };
  return v;
}

struct Row {
  double total = 0, shadow = 0, main = 0, aa = 0, readback = 0;
  ShadowSizeRange map;  // the shadow map's side over the timed frames
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Every configuration of one scene and size, frame by frame in turn; medians per configuration.
std::vector<Row> measureAll(const std::string& scene_path, const std::vector<std::string>& sets, int w, int h,
                            int frames) {
  struct Run {
    Scene scene;
    std::unique_ptr<RenderSession> session;
    std::vector<double> total, shadow, main, aa, readback;
    ShadowSizeRange map;
  };
  std::vector<Run> runs;
  for (const Variant& v : variants()) {
    std::vector<Override> o;
    for (const auto& s : sets) o.push_back(parseOverride(s));
    for (const auto& s : v.sets) o.push_back(parseOverride(s));
    Run r;
    r.scene = loadScene(scene_path, o);
    r.scene.render.width = w;
    r.scene.render.height = h;
    validateScene(r.scene, scene_path);
    r.session = std::make_unique<RenderSession>(r.scene);
    runs.push_back(std::move(r));
  }
  std::vector<uint8_t> rgba;
  const int warmup = 2;
  for (int i = 0; i < warmup + frames; ++i) {
    for (Run& r : runs) {
      const double t = i / r.scene.render.fps;
      if (!r.session->simulateTo(t)) throw InputError(scene_path + ": the simulation stopped: " + r.session->status());
      r.session->makeCurrent();  // the switch between the configurations' contexts is not the frame's
      const auto t0 = Clock::now();
      r.session->renderFrame(t, rgba);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (i < warmup) continue;
      const RenderStats& st = r.session->stats();
      r.total.push_back(ms);
      r.shadow.push_back(st.shadow_ms);
      r.main.push_back(st.main_ms);
      r.aa.push_back(st.resolve_ms);
      r.readback.push_back(st.readback_ms);
      r.map.add(st);
    }
  }
  std::vector<Row> rows;
  for (const Run& r : runs)
    rows.push_back({median(r.total), median(r.shadow), median(r.main), median(r.aa), median(r.readback), r.map});
  return rows;
}

int runBenchRender(const BenchRenderArgs& args) {
  // Every size and scene is checked before anything is measured: a typo in the last one does not
  // cost the minutes spent on the others.
  std::vector<std::pair<int, int>> sizes;
  for (const auto& size : args.sizes) {
    int w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(size.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192)
      throw InputError("--sizes " + size + ": expected WIDTHxHEIGHT between 16x16 and 8192x8192, e.g. 1280x720");
    sizes.emplace_back(w, h);
  }
  std::vector<Override> overrides;
  for (const auto& s : args.sets) overrides.push_back(parseOverride(s));
  for (const auto& scene : args.scenes) validateScene(loadScene(scene, overrides), scene);
  std::ostringstream md;
  utsname u{};
  uname(&u);
  const char* lp = std::getenv("LP_NUM_THREADS");
  std::string gl_name;
  {
    Scene probe = loadScene(args.scenes.front());
    probe.render.width = 64;
    probe.render.height = 64;
    RenderSession s(probe);
    gl_name = s.glRenderer() + " / " + s.glVersion();
  }
  md << "# Render speed\n\n"
     << "`ponyhop bench-render` (bench/cmd_bench_render.cpp): ms per frame, median of " << args.frames
     << " frames after 2 warm-up frames (the configurations take turns frame by frame), on " << u.machine << " with "
     << std::thread::hardware_concurrency() << " hardware threads, " << gl_name
     << ", LP_NUM_THREADS=" << (lp ? lp : "(unset)") << ", load average at the start " << loadAverage() << ".\n\n";
  if (!args.sets.empty()) {
    md << "Every configuration with:";
    for (const auto& s : args.sets) md << " `" << s << "`";
    md << ".\n\n";
  }
  md << "*render* is the wall time of one frame (all passes and the read-back); the pass columns are "
        "RenderStats (glFinish-bracketed: llvmpipe rasterizes a pass synchronously at its flush). "
        "*x floor* = render / the floor of the same scene and size (1 sample, no shadow, no ground). *shadow map*: "
        "the side of the shadow map over the timed frames, in texels (the renderer matches it to the frame: "
        "docs/RENDERING.md).\n\n";
  std::ostringstream summary, tables;
  summary << "## Final / floor\n\n"
          << "| scene | size | final (ms) | floor (ms) | x floor |\n"
          << "|---|---|---:|---:|---:|\n";
  for (const auto& scene : args.scenes) {
    for (const auto& [w, h] : sizes) {
      const std::string size = std::to_string(w) + "x" + std::to_string(h);
      tables << "## " << scene << " at " << w << "x" << h << "\n\n"
             << "| configuration | render | shadow | main | AA | read-back | x floor | shadow map |\n"
             << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
      const std::vector<Row> rows = measureAll(scene, args.sets, w, h, args.frames);
      for (size_t i = 0; i < rows.size(); ++i)
        std::fprintf(stderr, "bench-render: %s %s %-38s %7.1f ms\n", scene.c_str(), size.c_str(), variants()[i].name,
                     rows[i].total);
      const double floor_ms = rows[3].total;
      for (size_t i = 0; i < rows.size(); ++i) {
        const Row& r = rows[i];
        const std::string map = r.map.hi ? r.map.text() : "-";
        char line[256];
        std::snprintf(line, sizeof line, "| %s | %.1f | %.1f | %.1f | %.1f | %.1f | %.2f | %s |\n", variants()[i].name,
                      r.total, r.shadow, r.main, r.aa, r.readback, r.total / floor_ms, map.c_str());
        tables << line;
      }
      tables << "\n";
      char line[256];
      std::snprintf(line, sizeof line, "| %s | %s | %.1f | %.1f | %.2f |\n",
                    std::filesystem::path(scene).stem().c_str(), size.c_str(), rows[0].total, floor_ms,
                    rows[0].total / floor_ms);
      summary << line;
    }
  }
  md << summary.str() << "\n" << tables.str();
  md << "Load average at the end: " << loadAverage() << ".\n";
  std::fputs(md.str().c_str(), stdout);
  if (!args.out.empty()) {
    std::error_code ec;
    const auto parent = std::filesystem::path(args.out).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    const std::string tmp = args.out + ".tmp";
    std::ofstream f(tmp);
    f << md.str();
    f.close();
    if (!f || (std::filesystem::rename(tmp, args.out, ec), ec)) {
      std::fprintf(stderr, "ponyhop bench-render: %s: cannot write the table\n", args.out.c_str());
      return 1;
    }
    std::fprintf(stderr, "bench-render: table in %s\n", args.out.c_str());
  }
  return 0;
}

}  // namespace

CommandSpec benchRenderCommand() {
  auto args = std::make_shared<BenchRenderArgs>();
  CommandSpec cmd{"bench-render", "Render time per pass of the demo scenes in each quality configuration"};
  cmd.add("--scenes", args->scenes, "Scenes to render (default: the scenes of make demo, and ponytail_hopper)").list();
  cmd.add("--sizes", args->sizes, "Frame sizes, e.g. 1280x720,1920x1080").list();
  cmd.add("--frames", args->frames, "Timed frames per configuration (default 20)").within(1, 10000);
  cmd.add("--set", args->sets, "key=value overrides applied to every configuration (as render --set)");
  cmd.add("--out", args->out, "Markdown table to write (default docs/bench/render_table.md; empty: print only)");
  cmd.run = [args] { return runCommand("bench-render", [&] { return runBenchRender(*args); }); };
  return cmd;
}

}  // namespace ponyhop

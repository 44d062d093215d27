// `ponyhop render SCENE [--frames N] [--fps F] [--size WxH] [--out DIR] [--video F.mp4] [--set k=v]...`
//
// Output safety (app/output_safety.h, docs/RELIABILITY.md): every input and output path is
// checked before anything is written; frames go to a staging folder beside DIR under a lock, and
// only a run that succeeded swaps it in for DIR in one rename; SIGINT/SIGTERM stop cleanly.
// PNG encoding runs on worker threads and overlaps rendering.
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "app/output_safety.h"
#include "app/render_range.h"
#include "app/scene_args.h"
#include "app/ui_headless.h"
#include "engine/frame_writer.h"
#include "engine/render_session.h"
#include "engine/video.h"
#include "physics/stage_times.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;

struct RenderArgs {
  SceneArgs scene;
  int frames = 0;
  double fps = 0.0;
  std::string size;
  std::string out;
  std::string video;
  bool ui = false;
  std::string range;  // --range A:B (app/render_range.h)
  bool resume = false;
  bool transparent = false;
};

// Progress on stderr: rewritten in place on a terminal, a plain line every ~10 % otherwise.
class Progress {
 public:
  explicit Progress(int total) : total_(total), tty_(isatty(STDERR_FILENO)) {}
  void update(int done, double ms_per_frame) {
    if (tty_) {
      std::fprintf(stderr, "\rrender: frame %d/%d (%3.0f%%) %.1f ms/frame   ", done, total_, 100.0 * done / total_,
                   ms_per_frame);
      if (done == total_) std::fputc('\n', stderr);
    } else {
      const int step = std::max(1, total_ / 10);
      if (done % step == 0 || done == total_) {
        std::fprintf(stderr, "render: frame %d/%d (%.0f%%) %.1f ms/frame\n", done, total_, 100.0 * done / total_,
                     ms_per_frame);
      }
    }
  }

 private:
  int total_;
  bool tty_;
};

int interrupted(int sig, const std::string& out) {
  std::fprintf(stderr, "\nponyhop render: stopped by %s; the staged frames were removed, %s is untouched\n",
               sig == SIGINT ? "SIGINT" : "SIGTERM", out.c_str());
  return InterruptGuard::exitCode(sig);
}

// --range / --resume (app/render_range.h): a render farm's chunk or a resumed run, straight into
// `out` frame by frame; then the video of the whole folder when asked (not with --range).
int renderChunkCommand(const Scene& scene, const std::string& out, const FrameRange& range, const RenderArgs& args) {
  RenderSession session(scene);
  const int rc = renderChunk(session, scene.render.fps, out, range, args.resume);
  if (rc != 0 || args.video.empty()) return rc;
  VideoOptions vo;
  vo.fps = scene.render.fps;
  std::string err;
  if (!encodeVideo(out, args.video, vo, &err)) {
    std::fprintf(stderr, "ponyhop render: %s\n", err.c_str());
    return 1;
  }
  std::fprintf(stderr, "render: video %s\n", args.video.c_str());
  return 0;
}

int runRender(const RenderArgs& args) {
  // 1. Everything that can be wrong with the input is found before a file is touched.
  Scene scene = args.scene.load();
  if (args.fps > 0.0) scene.render.fps = args.fps;
  if (args.frames > 0) scene.render.frames = args.frames;
  if (!args.size.empty()) {
    int w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(args.size.c_str(), "%dx%d%c", &w, &h, &tail) != 2) {
      throw InputError("--size " + args.size + ": expected WIDTHxHEIGHT, e.g. 1280x720");
    }
    scene.render.width = w;
    scene.render.height = h;
  }
  if (args.transparent) scene.render.transparent = true;
  validateScene(scene, args.scene.path);
  const std::string out = args.out.empty() ? "out/" + fs::path(args.scene.path).stem().string() : args.out;
  std::error_code ec;
  if (!args.video.empty()) {
    // Checked before any rendering: writable, not an input, not inside the frames folder (which
    // is replaced whole).
    checkOutputFile("--video", args.video, sceneInputs(scene));
    const fs::path vdir = fs::weakly_canonical(fs::absolute(fs::path(args.video), ec).parent_path(), ec);
    const fs::path odir = fs::weakly_canonical(fs::absolute(fs::path(out), ec), ec);
    if (vdir == odir || samePath(args.video, out)) {
      throw InputError("--video " + args.video + ": is inside the frames folder " + out +
                       ", which each render replaces whole; put the video beside it");
    }
    if (!ffmpegAvailable())
      throw InputError("--video " + args.video + ": ffmpeg is not installed (apt-get install ffmpeg)");
  }
  std::string video_err;
  if (!args.video.empty() && videoContainer(args.video, &video_err).empty()) throw InputError("--video " + video_err);
  const bool chunk = !args.range.empty() || args.resume;
  if (chunk && args.ui)
    throw InputError("--range/--resume: not with --ui (the panel's plots depend on every frame before)");
  if (!args.range.empty() && !args.video.empty()) {
    throw InputError("--range with --video: a chunk is part of a video; encode the merged folder with `ponyhop video`");
  }
  const FrameRange range =
      args.range.empty() ? FrameRange{0, scene.render.frames - 1} : parseFrameRange(args.range, scene.render.frames);
  if (chunk) return renderChunkCommand(scene, out, range, args);  // without the folder lock: chunks share DIR
  InterruptGuard interrupt;
  FrameFolder folder("--out", out);  // checks DIR, takes its lock, cleans stale staging

  // --ui: the tuning panel beside the scene (the frame grows by the panel's width); the panel is
  // driven headless (app/ui_headless.h), the physics is the same stepping to the same times.
  std::unique_ptr<RenderSession> session;
  std::unique_ptr<HeadlessUi> ui;
  if (args.ui) {
    ui = std::make_unique<HeadlessUi>(scene, scene.render.width, scene.render.height);
  } else {
    session = std::make_unique<RenderSession>(scene);  // builds the world, the GL context and the renderer
  }
  const int out_w = ui ? ui->width() : session->width();
  const int out_h = ui ? ui->height() : session->height();
  const auto simulateTo = [&](double t) { return ui ? ui->sim().advanceTo(t) : session->simulateTo(t); };
  const auto status = [&]() { return ui ? ui->sim().stopMessage() : session->status(); };
  const int frames = scene.render.frames;
  const std::string& staging = folder.staging();

  // 2. Simulate, render, hand the pixels to the encoder threads.
  FrameWriter writer(staging, 2, 4);
  Progress progress(frames);
  double sim_ms = 0.0, render_ms = 0.0, wait_ms = 0.0;
  RenderStats passes;   // summed per-pass times (engine/renderer.h)
  ShadowSizeRange map;  // the shadow map's side over the frames
  const auto t_start = Clock::now();
  std::string err;
  for (int i = 0; i < frames; ++i) {
    if (InterruptGuard::signal()) break;
    const double t = i / scene.render.fps;
    auto t0 = Clock::now();
    const bool sim_ok = simulateTo(t);
    sim_ms += msSince(t0);
    if (!sim_ok) {
      writer.finish();
      std::fprintf(stderr,
                   "\nponyhop render: the simulation stopped before frame %d: %s\n"
                   "  no frame was written; %s is untouched\n",
                   i, status().c_str(), out.c_str());
      return 1;
    }
    t0 = Clock::now();
    std::vector<uint8_t> rgba;
    if (ui) {
      UiInput in;
      in.dt = 1.0 / scene.render.fps;
      ui->frame(in, &rgba, t);
    } else {
      session->renderFrame(t, rgba);
    }
    render_ms += msSince(t0);
    const RenderStats& st = ui ? ui->renderer().stats() : session->stats();
    passes.shadow_ms += st.shadow_ms;
    passes.main_ms += st.main_ms;
    passes.resolve_ms += st.resolve_ms;
    passes.readback_ms += st.readback_ms;
    passes.timed_on_gpu = st.timed_on_gpu;
    map.add(st);
    t0 = Clock::now();
    if (!writer.push(i, out_w, out_h, std::move(rgba), &err)) break;
    wait_ms += msSince(t0);
    progress.update(i + 1, msSince(t_start) / (i + 1));
  }
  const auto t_flush = Clock::now();
  const bool written = writer.finish(&err);
  wait_ms += msSince(t_flush);
  if (const int sig = InterruptGuard::signal()) return interrupted(sig, out);
  if (!written) {
    std::fprintf(stderr, "ponyhop render: writing frames failed: %s\n  %s is untouched\n", err.c_str(), out.c_str());
    return 1;
  }
  const double total_s = msSince(t_start) / 1000.0;

  // 3. The video from the staged frames (under a temporary name), then the frames swap in for
  // the old ones in one rename, then the video takes its name: nothing is replaced before
  // everything succeeded.
  double video_s = 0.0;
  const std::string video_tmp = args.video + ".partial-" + std::to_string(getpid());
  if (!args.video.empty()) {
    const auto t0 = Clock::now();
    VideoOptions vo;
    vo.fps = scene.render.fps;
    vo.container = videoContainer(args.video, nullptr);  // of the final name, not of video_tmp's
    const bool encoded = encodeVideo(staging, video_tmp, vo, &err);
    if (const int sig = InterruptGuard::signal()) {
      fs::remove(video_tmp, ec);
      return interrupted(sig, out);
    }
    if (!encoded) {
      fs::remove(video_tmp, ec);
      std::fprintf(stderr, "ponyhop render: %s\n  %s is untouched\n", err.c_str(), out.c_str());
      return 1;
    }
    video_s = msSince(t0) / 1000.0;
  }
  if (!folder.publish(&err)) {
    if (!args.video.empty()) fs::remove(video_tmp, ec);
    std::fprintf(stderr, "ponyhop render: %s\n", err.c_str());
    return 1;
  }
  if (!args.video.empty()) {
    fs::rename(video_tmp, args.video, ec);
    if (ec) {
      fs::remove(video_tmp, ec);
      std::fprintf(stderr, "ponyhop render: %s: %s (the frames are in %s)\n", args.video.c_str(), ec.message().c_str(),
                   out.c_str());
      return 1;
    }
  }
  std::fprintf(stderr,
               "render: %d frames %dx%d (%d samples) in %.2f s = %.1f ms/frame: simulate %.2f, render %.1f, "
               "encode %.1f on 2 worker threads (overlapped; the render loop waited %.1f ms/frame for it)\n",
               frames, out_w, out_h, scene.render.samples, total_s, 1000.0 * total_s / frames, sim_ms / frames,
               render_ms / frames, writer.meanEncodeMs(), wait_ms / frames);
  const std::string map_text = map.hi ? "shadow map " + map.text() + " texels a side" : "no shadow map";
  std::fprintf(stderr, "render: per pass (ms/frame, %s): shadow %.1f, main %.1f, resolve %.1f, read-back %.1f; %s\n",
               passes.timed_on_gpu ? "GPU timer queries" : "glFinish-bracketed", passes.shadow_ms / frames,
               passes.main_ms / frames, passes.resolve_ms / frames, passes.readback_ms / frames, map_text.c_str());
  std::fprintf(stderr, "render: frames in %s/\n", out.c_str());
  if (!args.video.empty()) std::fprintf(stderr, "render: video %s (%.1f s to encode)\n", args.video.c_str(), video_s);
  return 0;
}

}  // namespace

void addRenderCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand("render", "Render a scene headless into a PNG sequence (and a video)");
  args->scene.add(cmd);
  cmd->add_option("--frames", args->frames, "Number of frames (default: render.frames)")->check(CLI::Range(1, 1000000));
  cmd->add_option("--fps", args->fps, "Frames per second (default: render.fps)")->check(finiteIn(1.0, 1000.0));
  cmd->add_option("--size", args->size, "Image size WIDTHxHEIGHT (default: render.width x render.height)")
      ->check(nonEmpty());
  cmd->add_option("--out", args->out, "Output folder (default: out/SCENE_NAME); replaced whole by a run that succeeds")
      ->check(nonEmpty());
  cmd->add_option("--video", args->video, "Also encode a video: .mp4, .mov (H.264), .webm (VP9) or .gif (ffmpeg)")
      ->check(nonEmpty());
  cmd->add_flag("--ui", args->ui, "Draw the tuning panel beside the scene");
  cmd->add_option("--range", args->range,
                  "Render only frames A to B (A:B, inclusive), byte-identical to a full run's (docs/RENDER_FARM.md)");
  cmd->add_flag("--resume", args->resume, "Keep frames already written whole in --out; render the others");
  cmd->add_flag("--transparent", args->transparent, "No background: PNG frames with alpha (render.transparent)");
  cmd->callback([args, &exit_code] { exit_code = runCommand("render", [&] { return runRender(*args); }); });
}

}  // namespace ponyhop

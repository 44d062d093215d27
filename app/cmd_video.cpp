// `ponyhop video DIR --out F.mp4|.mov|.webm|.gif [--fps F]`: encodes DIR/frame_%05d.png (e.g. the
// folder a render farm's chunks were merged into) into the container the file name says.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "engine/frame_writer.h"
#include "engine/video.h"

namespace ponyhop {
namespace {

struct VideoArgs {
  std::string dir;
  std::string out;
  double fps = 30.0;
};

int runVideo(const VideoArgs& args) {
  std::string err;
  if (videoContainer(args.out, &err).empty()) {
    std::fprintf(stderr, "ponyhop video: --out %s\n", err.c_str());
    return 2;
  }
  std::error_code ec;
  if (!std::filesystem::exists(FrameWriter::framePath(args.dir, 0), ec)) {
    std::fprintf(stderr, "ponyhop video: %s: no frame_00000.png in this folder\n", args.dir.c_str());
    return 2;
  }
  if (!ffmpegAvailable()) {
    std::fprintf(stderr, "ponyhop video: ffmpeg is not installed (apt-get install ffmpeg)\n");
    return 2;
  }
  VideoOptions vo;
  vo.fps = args.fps;
  if (!encodeVideo(args.dir, args.out, vo, &err)) {
    std::fprintf(stderr, "ponyhop video: %s\n", err.c_str());
    return 1;
  }
  std::fprintf(stderr, "video: %s -> %s\n", args.dir.c_str(), args.out.c_str());
  return 0;
}

}  // namespace

void addVideoCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<VideoArgs>();
  auto* cmd = app.add_subcommand("video", "Encode a folder of frames (frame_00000.png, ...) into a video");
  cmd->add_option("DIR", args->dir, "Folder of frames")->required();
  cmd->add_option("--out", args->out, "Video file: .mp4, .mov (H.264), .webm (VP9) or .gif")->required();
  cmd->add_option("--fps", args->fps, "Frames per second")->check(CLI::Range(1.0, 1000.0));
  cmd->callback([args, &exit_code] { exit_code = runVideo(*args); });
}

}  // namespace ponyhop

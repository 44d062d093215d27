// H.264 mp4 from a PNG sequence, with the `ffmpeg` program (Debian package ffmpeg).
#pragma once

#include <string>

namespace ponyhop {

struct VideoOptions {
  double fps = 30.0;
  int crf = 18;                              // x264 quality (lower = better, 18 ~ visually lossless)
  std::string pattern = "frame_%05d.png";    // as written by FrameWriter
  int start_number = 0;
  std::string ffmpeg = "ffmpeg";             // program name or path
};

// True when the ffmpeg program can be started.
bool ffmpegAvailable(const std::string& ffmpeg = "ffmpeg");

// Encodes FRAME_DIR/pattern into `out_mp4` (libx264, yuv420p, +faststart; odd sizes are padded to
// even). Written to OUT.tmp first and renamed when ffmpeg succeeded, so a failed run never leaves a
// truncated video under the final name. False + a message with ffmpeg's stderr tail on failure.
bool encodeVideo(const std::string& frame_dir, const std::string& out_mp4, const VideoOptions& opt, std::string* err);

}  // namespace ponyhop

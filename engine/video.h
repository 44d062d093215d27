// A video from a PNG sequence, with the `ffmpeg` program (Debian package ffmpeg), in the container
// its file name says: .mp4 and .mov (H.264), .webm (VP9, keeps alpha), .gif (one palette per video).
#pragma once

#include <string>

namespace ponyhop {

struct VideoOptions {
  double fps = 30.0;
  int crf = 18;                              // x264 quality (lower = better, 18 ~ visually lossless)
  std::string pattern = "frame_%05d.png";    // as written by FrameWriter
  int start_number = 0;
  std::string ffmpeg = "ffmpeg";             // program name or path
  std::string container;                     // "" = from the output's extension (videoContainer)
};

// True when the ffmpeg program can be started.
bool ffmpegAvailable(const std::string& ffmpeg = "ffmpeg");

// The containers encodeVideo writes: "mp4", "mov", "webm", "gif" (lower case, no dot).
// "" with a message naming the file and what is allowed, for any other extension.
std::string videoContainer(const std::string& path, std::string* err);

// Encodes FRAME_DIR/pattern into `out_mp4` in its container (mp4/mov: libx264, yuv420p,
// +faststart; webm: libvpx-vp9, yuva420p; gif: palettegen + paletteuse; odd sizes are padded to
// even for the yuv formats). Written to OUT.tmp first and renamed when ffmpeg succeeded, so a failed run never leaves a
// truncated video under the final name. False + a message with ffmpeg's stderr tail on failure.
bool encodeVideo(const std::string& frame_dir, const std::string& out_mp4, const VideoOptions& opt, std::string* err);

}  // namespace ponyhop

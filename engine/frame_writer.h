// PNG output. stb_image_write's own deflate is slow (about 2x the render time of a 720p frame on 2 cores), so
// frame_writer.cpp compiles stb_image_write privately (static symbols, no clash with libstb.a)
// with its compressor routed to zlib's compress2 at a fast level, and FrameWriter encodes on
// worker threads so that encoding overlaps rendering.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "engine/image.h"  // Image (RGBA8, top row first)

namespace ponyhop {

// zlib level used for frames (1: fastest; measured in docs/RENDERING.md).
inline constexpr int kPngZlibLevel = 1;

// Encodes and writes `path` atomically: PATH.tmp first, then rename(2), so a reader (or a crash)
// never sees a half-written PNG. False + "PATH: reason" on failure.
bool writePngAtomic(const std::string& path, int width, int height, const uint8_t* rgba, std::string* err,
                    int zlib_level = kPngZlibLevel);
// Decodes a PNG into RGBA8 (stb_image; same as loadPng of engine/image.h, with an optional).
std::optional<Image> readPng(const std::string& path, std::string* err);

// Asynchronous numbered frames: DIR/frame_00000.png, DIR/frame_00001.png, ...
// push() hands the pixels to 1-2 worker threads through a bounded queue (blocks when the queue is
// full, so memory stays bounded when encoding is slower than rendering). The first error stops
// further writes and is returned by push()/finish().
class FrameWriter {
 public:
  FrameWriter(std::string dir, int threads = 2, size_t max_queue = 4);
  ~FrameWriter();  // finish()es
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;

  static std::string framePath(const std::string& dir, int index);  // DIR/frame_%05d.png

  // Queues frame `index`; false (with the first error) if a write failed earlier.
  bool push(int index, int width, int height, std::vector<uint8_t> rgba, std::string* err = nullptr);
  // Waits for every queued frame; false with the first error.
  bool finish(std::string* err = nullptr);

  int framesWritten() const;
  double meanEncodeMs() const;  // per frame: PNG encode + write + rename, on a worker
  std::string error() const;

 private:
  struct Job {
    int index, width, height;
    std::vector<uint8_t> rgba;
  };
  void worker();

  std::string dir_;
  size_t max_queue_;
  mutable std::mutex mu_;
  std::condition_variable cv_work_, cv_space_, cv_idle_;
  std::deque<Job> queue_;
  int busy_ = 0;
  bool stop_ = false;
  std::string error_;
  int written_ = 0;
  double encode_ms_total_ = 0.0;
  std::vector<std::thread> threads_;
};

}  // namespace ponyhop

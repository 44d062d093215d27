#include "engine/frame_writer.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "physics/stage_times.h"

// --- Our own copy of stb_image_write ----------------------------------------------------------
// STB_IMAGE_WRITE_STATIC: every stbi_write_* symbol is static to this file, so this copy never
// clashes with the one inside libstb.a. STBIW_ZLIB_COMPRESS: replace stb's simple deflate with
// zlib (several times faster at level 1 and smaller files). stb calls it with its own `quality`
// (stbi_write_png_compression_level, default 8); we ignore that and use the level of the current
// thread, set by encodePng.
static thread_local int tl_zlib_level = 1;
static unsigned char* zlibCompress(unsigned char* data, int data_len, int* out_len, int /*quality*/) {
  uLongf len = compressBound(uLong(data_len));
  unsigned char* out = static_cast<unsigned char*>(std::malloc(len));
  if (!out) return nullptr;
  if (compress2(out, &len, data, uLong(data_len), tl_zlib_level) != Z_OK) {
    std::free(out);
    return nullptr;
  }
  *out_len = int(len);
  return out;
}
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBIW_ZLIB_COMPRESS zlibCompress
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wshadow"
#endif
#include <stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
// stb tries all five PNG row filters on every row and keeps the best guess: that search cost ~4x
// the zlib time on our frames. One fixed filter, Sub (each byte minus its left neighbour), turns
// the flat background/ground runs into zeros and came out both faster (97 -> 23 ms for a 720p
// frame) and slightly smaller than the search (see docs/RENDERING.md). Set once, before any
// thread starts (stb reads it without a lock).
static const bool kFilterForced = [] {
  stbi_write_force_png_filter = 1;
  return true;
}();

namespace ponyhop {

namespace {

bool writeFileAtomic(const std::string& path, const unsigned char* data, size_t size, std::string* err) {
  const std::string tmp = path + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    if (err) *err = tmp + ": cannot open for writing (" + std::strerror(errno) + ")";
    return false;
  }
  const bool ok_write = std::fwrite(data, 1, size, f) == size;
  const int saved_errno = errno;
  const bool ok_close = std::fclose(f) == 0;
  if (!ok_write || !ok_close) {
    if (err) *err = tmp + ": write failed (" + std::strerror(ok_write ? errno : saved_errno) + ")";
    std::remove(tmp.c_str());
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    if (err) *err = path + ": cannot rename " + tmp + " (" + std::strerror(errno) + ")";
    std::remove(tmp.c_str());
    return false;
  }
  return true;
}

}  // namespace

bool writePngAtomic(const std::string& path, int width, int height, const uint8_t* rgba, std::string* err,
                    int zlib_level) {
  if (width <= 0 || height <= 0 || !rgba) {
    if (err) *err = path + ": empty image";
    return false;
  }
  tl_zlib_level = std::clamp(zlib_level, 0, 9);
  int len = 0;
  unsigned char* png = stbi_write_png_to_mem(rgba, width * 4, width, height, 4, &len);
  if (!png) {
    if (err) *err = path + ": PNG encoding failed (out of memory?)";
    return false;
  }
  const bool ok = writeFileAtomic(path, png, size_t(len), err);
  STBIW_FREE(png);
  return ok;
}

std::optional<Image> readPng(const std::string& path, std::string* err) {
  Image img = loadPng(path, err);
  if (img.empty()) return std::nullopt;
  return img;
}

// --- FrameWriter ------------------------------------------------------------------------------

FrameWriter::FrameWriter(std::string dir, int threads, size_t max_queue)
    : dir_(std::move(dir)), max_queue_(std::max<size_t>(max_queue, 1)) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) error_ = dir_ + ": cannot create the folder (" + ec.message() + ")";
  threads = std::clamp(threads, 1, 8);
  for (int i = 0; i < threads; ++i) threads_.emplace_back([this] { worker(); });
}

FrameWriter::~FrameWriter() {
  finish(nullptr);
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  cv_work_.notify_all();
  for (auto& t : threads_) t.join();
}

std::string FrameWriter::framePath(const std::string& dir, int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%05d.png", index);
  return (std::filesystem::path(dir) / name).string();
}

bool FrameWriter::push(int index, int width, int height, std::vector<uint8_t> rgba, std::string* err) {
  std::unique_lock<std::mutex> lock(mu_);
  cv_space_.wait(lock, [&] { return queue_.size() < max_queue_ || !error_.empty(); });
  if (!error_.empty()) {
    if (err) *err = error_;
    return false;
  }
  queue_.push_back(Job{index, width, height, std::move(rgba)});
  lock.unlock();
  cv_work_.notify_one();
  return true;
}

bool FrameWriter::finish(std::string* err) {
  std::unique_lock<std::mutex> lock(mu_);
  cv_idle_.wait(lock, [&] { return (queue_.empty() && busy_ == 0) || !error_.empty(); });
  // After an error, drop what is still queued (the user gets the error now, not after minutes).
  if (!error_.empty()) queue_.clear();
  cv_idle_.wait(lock, [&] { return busy_ == 0; });
  if (!error_.empty()) {
    if (err) *err = error_;
    return false;
  }
  return true;
}

void FrameWriter::worker() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_work_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stop_ and nothing left
      job = std::move(queue_.front());
      queue_.pop_front();
      ++busy_;
    }
    cv_space_.notify_one();
    const auto t0 = Clock::now();
    std::string e;
    const bool ok = writePngAtomic(framePath(dir_, job.index), job.width, job.height, job.rgba.data(), &e);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    {
      std::lock_guard<std::mutex> lock(mu_);
      --busy_;
      if (ok) {
        ++written_;
        encode_ms_total_ += ms;
      } else if (error_.empty()) {
        error_ = e;
      }
    }
    cv_idle_.notify_all();
    cv_space_.notify_all();
  }
}

int FrameWriter::framesWritten() const {
  std::lock_guard<std::mutex> lock(mu_);
  return written_;
}
double FrameWriter::meanEncodeMs() const {
  std::lock_guard<std::mutex> lock(mu_);
  return written_ ? encode_ms_total_ / written_ : 0.0;
}
std::string FrameWriter::error() const {
  std::lock_guard<std::mutex> lock(mu_);
  return error_;
}

}  // namespace ponyhop

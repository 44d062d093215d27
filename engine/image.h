// RGBA8 images in memory and their PNG files (stb_image / stb_image_write).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ponyhop {

// Row-major, top row first, 4 bytes per pixel (R, G, B, A; straight, not premultiplied alpha).
struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // width * height * 4 bytes

  Image() = default;
  // A width x height image filled with one colour (opaque black unless told).
  Image(int w, int h, uint8_t r = 0, uint8_t g = 0, uint8_t b = 0, uint8_t a = 255);

  bool empty() const { return width <= 0 || height <= 0; }
  uint8_t* px(int x, int y) { return rgba.data() + (static_cast<size_t>(y) * width + x) * 4; }
  const uint8_t* px(int x, int y) const { return rgba.data() + (static_cast<size_t>(y) * width + x) * 4; }
};

// Limits of images read (docs/RELIABILITY.md): the header is read first and a larger image is
// refused before its pixels are allocated.
inline constexpr int kMaxImageSide = 16384;
inline constexpr int64_t kMaxImagePixels = 64'000'000;
inline constexpr size_t kMaxImageFileBytes = size_t(256) << 20;

// Reads any PNG (grey, grey+alpha, RGB, RGBA; 8 or 16 bit) as RGBA8. On failure returns an
// empty image and, when `err` is given, a message naming the file and the reason.
// Only a regular file is opened (a FIFO or device is refused, nothing blocks).
Image loadPng(const std::string& path, std::string* err = nullptr);
// The same from the file's bytes (`source` names it in messages).
Image decodePng(const std::string& bytes, const std::string& source, std::string* err = nullptr);

// Writes `image` as an RGBA PNG. Atomic: writes `path`.tmp, then renames it over `path`, so a
// reader never sees a half-written file. Returns false with a message naming the file on failure.
bool savePng(const std::string& path, const Image& image, std::string* err = nullptr);

}  // namespace ponyhop

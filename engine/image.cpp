#include "engine/image.h"

#include <stb_image.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "engine/frame_writer.h"
#include "sim/input_file.h"

namespace ponyhop {

Image::Image(int w, int h, uint8_t r, uint8_t g, uint8_t b, uint8_t a) : width(w), height(h) {
  rgba.resize(static_cast<size_t>(w > 0 ? w : 0) * (h > 0 ? h : 0) * 4);
  for (size_t i = 0; i < rgba.size(); i += 4) {
    rgba[i] = r;
    rgba[i + 1] = g;
    rgba[i + 2] = b;
    rgba[i + 3] = a;
  }
}

Image decodePng(const std::string& bytes, const std::string& source, std::string* err) {
  if (bytes.size() > size_t(INT32_MAX)) {
    if (err) *err = source + ": too large";
    return {};
  }
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int len = int(bytes.size());
  int w = 0, h = 0, channels = 0;
  // The header first: the size is checked before a byte of pixels is allocated.
  if (!stbi_info_from_memory(data, len, &w, &h, &channels)) {
    if (err) *err = source + ": cannot read as an image (" + stbi_failure_reason() + ")";
    return {};
  }
  if (w <= 0 || h <= 0 || w > kMaxImageSide || h > kMaxImageSide || int64_t(w) * int64_t(h) > kMaxImagePixels) {
    if (err) {
      *err = source + ": the image declares " + std::to_string(w) + "x" + std::to_string(h) + " pixels; the limit is " +
             std::to_string(kMaxImageSide) + " per side and " + std::to_string(kMaxImagePixels / 1000000) +
             " megapixels";
    }
    return {};
  }
  // Ask stb for 4 channels whatever the file holds: grey/RGB get A = 255, 16-bit is reduced to 8.
  unsigned char* pixels = stbi_load_from_memory(data, len, &w, &h, &channels, 4);
  if (!pixels) {
    if (err) *err = source + ": cannot read as an image (" + stbi_failure_reason() + ")";
    return {};
  }
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(pixels, pixels + static_cast<size_t>(w) * h * 4);
  stbi_image_free(pixels);
  return img;
}

Image loadPng(const std::string& path, std::string* err) {
  std::string bytes;
  if (!readInputFile(path, kMaxImageFileBytes, "PNG file", &bytes, err)) return {};
  return decodePng(bytes, path, err);
}

bool savePng(const std::string& path, const Image& image, std::string* err) {
  if (image.empty() || image.rgba.size() != static_cast<size_t>(image.width) * image.height * 4) {
    if (err) *err = path + ": refusing to write an empty or inconsistent image";
    return false;
  }
  // writePngAtomic checks every write and the close (a full disk is an error, not a 0-byte file).
  return writePngAtomic(path, image.width, image.height, image.rgba.data(), err, 9);
}

}  // namespace ponyhop

#include "engine/image.h"

#include <stb_image.h>
#include <stb_image_write.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

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

Image loadPng(const std::string& path, std::string* err) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    if (err) *err = path + ": no such file";
    return {};
  }
  int w = 0, h = 0, channels = 0;
  // Ask stb for 4 channels whatever the file holds: grey/RGB get A = 255, 16-bit is reduced to 8.
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 4);
  if (!data) {
    if (err) *err = path + ": cannot read as an image (" + stbi_failure_reason() + ")";
    return {};
  }
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(data, data + static_cast<size_t>(w) * h * 4);
  stbi_image_free(data);
  return img;
}

bool savePng(const std::string& path, const Image& image, std::string* err) {
  if (image.empty() || image.rgba.size() != static_cast<size_t>(image.width) * image.height * 4) {
    if (err) *err = path + ": refusing to write an empty or inconsistent image";
    return false;
  }
  const std::string tmp = path + ".tmp";
  errno = 0;
  if (!stbi_write_png(tmp.c_str(), image.width, image.height, 4, image.rgba.data(), image.width * 4)) {
    if (err) *err = tmp + ": cannot write PNG (" + (errno ? std::strerror(errno) : "write failed") + ")";
    std::remove(tmp.c_str());
    return false;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);  // atomic on POSIX within one filesystem
  if (ec) {
    if (err) *err = path + ": cannot rename " + tmp + " into place (" + ec.message() + ")";
    std::remove(tmp.c_str());
    return false;
  }
  return true;
}

}  // namespace ponyhop

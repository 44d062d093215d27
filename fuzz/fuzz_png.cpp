// libFuzzer target: the PNG reader behind `ponyhop diff` (engine/image: header limits, then
// stb_image), and the comparator on what was read.
#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/image.h"
#include "engine/image_diff.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::string err;
  const ponyhop::Image img = ponyhop::decodePng(bytes, "fuzz.png", &err);
  if (img.empty()) return 0;
  if (img.rgba.size() != size_t(img.width) * size_t(img.height) * 4) __builtin_trap();
  if (size_t(img.width) * size_t(img.height) <= 256 * 256) {
    ponyhop::Image diff;
    (void)ponyhop::compareImages(img, img, ponyhop::DiffOptions{}, &diff);
  }
  return 0;
}

#include "app/render_range.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "engine/frame_writer.h"
#include "engine/render_session.h"
#include "physics/stage_times.h"
#include "sim/input_error.h"

namespace ponyhop {

FrameRange parseFrameRange(const std::string& text, int frames) {
  const std::string allowed = " (allowed: A:B, A: or A, frames 0 to " + std::to_string(frames - 1) + ", A <= B)";
  FrameRange r;
  int a = 0, b = 0, n = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d:%d%c", &a, &b, &tail) == 2) {
    r = {a, b};
  } else if (std::sscanf(text.c_str(), "%d:%n", &a, &n) == 1 && n == int(text.size())) {
    r = {a, frames - 1};
  } else if (std::sscanf(text.c_str(), "%d%c", &a, &tail) == 1) {
    r = {a, a};
  } else {
    throw InputError("--range " + text + ": not a frame range" + allowed);
  }
  if (r.first < 0 || r.last < r.first || r.last >= frames) {
    throw InputError("--range " + text + ": outside the " + std::to_string(frames) + " frames" + allowed);
  }
  return r;
}

int renderChunk(RenderSession& session, double fps, const std::string& out, FrameRange range, bool resume) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    std::fprintf(stderr, "ponyhop render: %s: cannot create the output folder: %s\n", out.c_str(),
                 ec.message().c_str());
    return 1;
  }
  const auto t0 = Clock::now();
  FrameWriter writer(out, 2, 4);
  std::string err;
  int rendered = 0, kept = 0;
  for (int i = 0; i <= range.last; ++i) {
    const double t = i / fps;
    if (!session.simulateTo(t)) {
      writer.finish();
      std::fprintf(stderr, "ponyhop render: the simulation stopped before frame %d: %s\n", i, session.status().c_str());
      return 1;
    }
    const bool mine = range.contains(i);
    if (!mine || (resume && pngIsWhole(FrameWriter::framePath(out, i)))) {
      session.skipFrame(t);  // the follow camera moves on as in a full run
      kept += mine ? 1 : 0;
      continue;
    }
    std::vector<uint8_t> rgba;
    session.renderFrame(t, rgba);
    if (!writer.push(i, session.width(), session.height(), std::move(rgba), &err)) break;
    ++rendered;
  }
  if (!writer.finish(&err)) {
    std::fprintf(stderr, "ponyhop render: writing frames failed: %s\n", err.c_str());
    return 1;
  }
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::fprintf(stderr, "render: frames %d to %d: %d rendered, %d already there (--resume), in %.2f s -> %s/\n",
               range.first, range.last, rendered, kept, s, out.c_str());
  return 0;
}

bool pngIsWhole(const std::string& path) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  static const unsigned char kIend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  const std::streamoff size = in.tellg();
  if (size < 8 + 12) return false;
  unsigned char head[8], end[12];
  in.seekg(0);
  in.read(reinterpret_cast<char*>(head), 8);
  in.seekg(size - 12);
  in.read(reinterpret_cast<char*>(end), 12);
  return in && std::memcmp(head, kSignature, 8) == 0 && std::memcmp(end, kIend, 12) == 0;
}

}  // namespace ponyhop

#include "sim/grid_cache.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <utility>
#include <vector>

#include "physics/mesh_sdf.h"

namespace ponyhop {

namespace {

// The file: this magic, the key, the origin (3 doubles), the dims (3 int32), the cell and the
// Lipschitz bound (doubles), the node count (uint64), the values (float), then an FNV-1a checksum
// (uint64) of every byte before it. Native byte order: the files serve this machine.
constexpr char kGridFileMagic[16] = "ponyhop-grid-1\n";

uint64_t gridFileChecksum(const char* p, size_t n) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(p[i])) * 1099511628211ull;
  return h;
}

template <class T>
void appendRaw(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// Reads a T at `at` and moves past it; false when the bytes run out.
template <class T>
bool readRaw(const std::string& in, size_t& at, T& v) {
  if (in.size() - at < sizeof(T)) return false;
  std::memcpy(&v, in.data() + at, sizeof(T));
  at += sizeof(T);
  return true;
}

class FileGridStore final : public GridStore {
 public:
  explicit FileGridStore(std::string folder) : folder_(std::move(folder)) {}

  bool load(uint64_t key, SignedDistanceGrid& grid) const override {
    std::ifstream f(path(key), std::ios::binary);
    if (!f) return false;
    const std::string in((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (in.size() < sizeof(kGridFileMagic) + sizeof(uint64_t) ||
        in.compare(0, sizeof(kGridFileMagic), kGridFileMagic, sizeof(kGridFileMagic)) != 0)
      return false;
    const size_t body = in.size() - sizeof(uint64_t);
    uint64_t sum = 0;
    std::memcpy(&sum, in.data() + body, sizeof(sum));
    if (sum != gridFileChecksum(in.data(), body)) return false;
    size_t at = sizeof(kGridFileMagic);
    uint64_t stored = 0, count = 0;
    Eigen::Vector3d origin;
    int32_t dims[3];
    double cell = 0.0, lipschitz = 0.0;
    if (!readRaw(in, at, stored) || stored != key) return false;
    for (int a = 0; a < 3; ++a)
      if (!readRaw(in, at, origin(a))) return false;
    for (int32_t& d : dims)
      if (!readRaw(in, at, d)) return false;
    if (!readRaw(in, at, cell) || !readRaw(in, at, lipschitz) || !readRaw(in, at, count)) return false;
    if (count != (body - at) / sizeof(float) || (body - at) % sizeof(float) != 0) return false;
    std::vector<float> values(count);
    std::memcpy(values.data(), in.data() + at, count * sizeof(float));
    return grid.assign(origin, Eigen::Vector3i(dims[0], dims[1], dims[2]), cell, lipschitz, std::move(values)).ok();
  }

  // Written whole to a file of this process's own, then renamed over the name: a reader sees the
  // old file or the new one, never half of one, however many processes write at once.
  void save(uint64_t key, const SignedDistanceGrid& grid) const override {
    std::string out(kGridFileMagic, sizeof(kGridFileMagic));
    appendRaw(out, key);
    for (int a = 0; a < 3; ++a) appendRaw(out, grid.origin()(a));
    for (int a = 0; a < 3; ++a) appendRaw(out, static_cast<int32_t>(grid.dims()(a)));
    appendRaw(out, grid.cell());
    appendRaw(out, grid.lipschitz());
    appendRaw(out, static_cast<uint64_t>(grid.values().size()));
    out.append(reinterpret_cast<const char*>(grid.values().data()), grid.values().size() * sizeof(float));
    appendRaw(out, gridFileChecksum(out.data(), out.size()));
    std::error_code ec;
    std::filesystem::create_directories(folder_, ec);
    const std::string final_path = path(key);
    const std::string temp = final_path + ".tmp" + std::to_string(::getpid());
    {
      std::ofstream f(temp, std::ios::binary | std::ios::trunc);
      if (!f || !f.write(out.data(), static_cast<std::streamsize>(out.size())) || !f.flush()) {
        std::filesystem::remove(temp, ec);
        return;
      }
    }
    std::filesystem::rename(temp, final_path, ec);
    if (ec) std::filesystem::remove(temp, ec);
  }

 private:
  std::string path(uint64_t key) const {
    char name[40];
    std::snprintf(name, sizeof(name), "grid-%016llx.bin", static_cast<unsigned long long>(key));
    return (std::filesystem::path(folder_) / name).string();
  }

  std::string folder_;
};

}  // namespace

std::shared_ptr<const GridStore> fileGridStore(std::string folder) {
  return std::make_shared<FileGridStore>(std::move(folder));
}

void useGridCacheFromEnvironment() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (const char* folder = std::getenv("PONYHOP_GRID_CACHE"); folder && *folder) setGridStore(fileGridStore(folder));
  });
}

}  // namespace ponyhop

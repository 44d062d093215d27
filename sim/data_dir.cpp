#include "sim/data_dir.h"

#include <cstdlib>
#include <filesystem>

namespace ponyhop {
namespace fs = std::filesystem;

namespace {

bool holdsAssets(const fs::path& d) {
  std::error_code ec;
  return !d.empty() && fs::is_directory(d / "assets" / "scenes", ec);
}

std::string findDataDir() {
  if (const char* env = std::getenv("PONYHOP_DATA_DIR"); env && *env) return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const fs::path bin = exe.parent_path();
  // PREFIX/BINDIR/ponyhop -> PREFIX/DATADIR/ponyhop: climb one folder per component of BINDIR.
  fs::path prefix = bin;
  for ([[maybe_unused]] const auto& part : fs::path(PONYHOP_INSTALL_BINDIR)) prefix = prefix.parent_path();
  const fs::path data = PONYHOP_INSTALL_DATADIR;
  for (const fs::path& d : {prefix / data, bin / data, bin.parent_path() / data}) {
    if (holdsAssets(d)) return fs::weakly_canonical(d, ec).string();
  }
  return "";
}

}  // namespace

const std::string& dataDir() {
  static const std::string dir = findDataDir();
  return dir;
}

std::string resolveSceneFile(const std::string& path) {
  std::error_code ec;
  const fs::path p(path);
  if (path.empty() || p.is_absolute() || fs::exists(p, ec) || dataDir().empty()) return path;
  const fs::path under = fs::path(dataDir()) / p;
  if (fs::is_regular_file(under, ec)) return under.string();
  const fs::path named = fs::path(dataDir()) / "assets" / "scenes" / (path + ".json");
  if (p.extension().empty() && !p.has_parent_path() && fs::is_regular_file(named, ec)) return named.string();
  return path;
}

const char* versionString() { return PONYHOP_VERSION; }

}  // namespace ponyhop

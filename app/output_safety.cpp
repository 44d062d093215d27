#include "app/output_safety.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <regex>

#include "engine/frame_writer.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;

std::string errnoText() { return std::strerror(errno); }

// "a FIFO", "a device", ... for a path that exists and is not what was asked.
const char* kindOf(const struct stat& st) {
  if (S_ISDIR(st.st_mode)) return "a folder";
  if (S_ISFIFO(st.st_mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "a device";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  if (S_ISREG(st.st_mode)) return "a file";
  return "not a regular file";
}

// The folder that will hold `path`: created when missing, probed with a file of our own.
void checkWritableFolder(const std::string& option, const std::string& path, const fs::path& folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw InputError(option + " " + path + ": cannot create the folder " + folder.string() + ": " + ec.message());
  const std::string probe = (folder / (".ponyhop-probe-" + std::to_string(getpid()))).string();
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    throw InputError(option + " " + path + ": cannot create files in " + folder.string() + ": " + errnoText());
  }
  ::close(fd);
  ::unlink(probe.c_str());
}

fs::path folderOf(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

std::string stripSlashes(std::string s) {
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  return s;
}

const std::regex& frameName() {
  static const std::regex re("frame_\\d{5,}\\.png");
  return re;
}

volatile sig_atomic_t g_signal = 0;
struct sigaction g_old_int {
}, g_old_term{};

void onSignal(int sig) { g_signal = sig; }

}  // namespace

std::vector<std::string> sceneInputs(const Scene& scene) {
  std::vector<std::string> in{scene.path};
  if (scene.head) {
    in.push_back(resolveScenePath(scene.head->mesh, scene.path));
    in.push_back(resolveClipPath(scene.head->animation.clip, scene.path));
  }
  return in;
}

bool samePath(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return ca == cb;
}

void checkOutputFile(const std::string& option, const std::string& path, const std::vector<std::string>& inputs) {
  if (path.empty()) throw InputError(option + ": the path must not be empty");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    throw InputError(option + " " + path + ": is " + kindOf(st) + "; give the path of a file to write");
  }
  for (const auto& in : inputs) {
    if (!in.empty() && samePath(path, in)) {
      throw InputError(option + " " + path + ": is an input of this run (" + in + "); it would be overwritten");
    }
  }
  checkWritableFolder(option, path, folderOf(path));
}

// --- FrameFolder -------------------------------------------------------------------------------

FrameFolder::FrameFolder(const std::string& option, const std::string& dir_in) : dir_(stripSlashes(dir_in)) {
  if (dir_.empty()) throw InputError(option + ": the path must not be empty");
  const fs::path dir(dir_);
  if (dir.filename().empty() || dir.filename() == "." || dir.filename() == "..") {
    throw InputError(option + " " + dir_ + ": name the frames folder itself (e.g. out/" + "scene)");
  }
  struct stat st {};
  bool exists = false;
  if (::lstat(dir_.c_str(), &st) == 0) {
    exists = true;
    if (S_ISLNK(st.st_mode)) throw InputError(option + " " + dir_ + ": is a symbolic link; give the folder itself");
    if (!S_ISDIR(st.st_mode))
      throw InputError(option + " " + dir_ + ": exists and is " + kindOf(st) + ", not a folder");
  }
  const fs::path parent = folderOf(dir_);
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw InputError(option + " " + dir_ + ": cannot create the folder " + parent.string() + ": " + ec.message());
  struct stat pst {};
  if (exists && ::stat(parent.c_str(), &pst) == 0 && pst.st_dev != st.st_dev) mount_point_ = true;

  // Only frames in DIR: the whole folder is replaced, nothing else may be lost with it.
  if (exists) {
    std::vector<std::string> others;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (std::regex_match(name, frameName())) continue;
      if (mount_point_ && (name == "lost+found" || name.rfind(".partial-", 0) == 0)) continue;
      others.push_back(name);
    }
    if (ec) throw InputError(option + " " + dir_ + ": cannot list the folder: " + ec.message());
    if (!others.empty()) {
      std::string list;
      for (size_t i = 0; i < others.size() && i < 3; ++i) list += (i ? ", " : "") + others[i];
      if (others.size() > 3) list += ", ... (" + std::to_string(others.size()) + " in all)";
      throw InputError(option + " " + dir_ + ": holds files that are not frames (" + list +
                       "); a render replaces the whole folder, so give an empty or a frames-only folder");
    }
  }

  // The lock: one render per folder at a time. The holder's pid is in the file for the message.
  lock_path_ = dir_ + ".lock";
  for (int attempt = 0;; ++attempt) {
    lock_fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd_ < 0)
      throw InputError(option + " " + dir_ + ": cannot create the lock " + lock_path_ + ": " + errnoText());
    if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
      char buf[256] = {};
      const ssize_t n = ::pread(lock_fd_, buf, sizeof(buf) - 1, 0);
      ::close(lock_fd_);
      lock_fd_ = -1;
      std::string holder = n > 0 ? std::string(buf, size_t(n)) : "another process";
      while (!holder.empty() && holder.back() == '\n') holder.pop_back();
      throw InputError(option + " " + dir_ + ": another render is writing this folder (" + holder + ", lock " +
                       lock_path_ + "); wait for it to end or choose another " + option);
    }
    // The holder before us may have removed the file after we opened it: lock the file that is
    // at the path now.
    struct stat a {
    }, b{};
    if (::fstat(lock_fd_, &a) == 0 && ::stat(lock_path_.c_str(), &b) == 0 && a.st_ino == b.st_ino &&
        a.st_dev == b.st_dev) {
      break;
    }
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (attempt > 10) throw InputError(option + " " + dir_ + ": cannot take the lock " + lock_path_);
  }
  {
    char buf[160];
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char when[32];
    std::strftime(when, sizeof(when), "%Y-%m-%d %H:%M:%S UTC", &tm);
    const int n = std::snprintf(buf, sizeof(buf), "ponyhop render, pid %d, since %s\n", int(getpid()), when);
    if (::ftruncate(lock_fd_, 0) != 0 || ::pwrite(lock_fd_, buf, size_t(n), 0) != n) {
      // The lock holds without the text; only the message of a second run is poorer.
    }
  }

  // Holding the lock, every staging folder beside (or in) DIR is from a run that was killed.
  const fs::path stage_parent = mount_point_ ? dir : parent;
  const std::string prefix = mount_point_ ? ".partial-" : dir.filename().string() + ".partial-";
  for (const auto& e : fs::directory_iterator(stage_parent, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0) fs::remove_all(e.path(), ec);
  }
  staging_ = (stage_parent / (prefix + std::to_string(getpid()))).string();
  fs::remove_all(staging_, ec);
  fs::create_directories(staging_, ec);
  if (ec)
    throw InputError(option + " " + dir_ + ": cannot create the staging folder " + staging_ + ": " + ec.message());
}

FrameFolder::~FrameFolder() {
  std::error_code ec;
  if (!staging_.empty()) fs::remove_all(staging_, ec);
  if (lock_fd_ >= 0) {
    ::unlink(lock_path_.c_str());  // while still holding it: the next run locks a new file
    ::close(lock_fd_);
  }
}

bool FrameFolder::publish(std::string* err) {
  std::error_code ec;
  if (mount_point_) {
    // DIR cannot be renamed (it is a mount point): move the frames in one by one, then remove
    // the old frames beyond the new count. Not atomic; the lock still keeps other runs out.
    int count = 0;
    for (const auto& e : fs::directory_iterator(staging_, ec)) {
      if (std::regex_match(e.path().filename().string(), frameName())) ++count;
    }
    for (int i = 0; i < count; ++i) {
      fs::rename(FrameWriter::framePath(staging_, i), FrameWriter::framePath(dir_, i), ec);
      if (ec) {
        if (err) *err = FrameWriter::framePath(dir_, i) + ": " + ec.message();
        return false;
      }
    }
    for (const auto& e : fs::directory_iterator(dir_, ec)) {
      const std::string name = e.path().filename().string();
      if (std::regex_match(name, frameName()) && std::stol(name.substr(6)) >= count) fs::remove(e.path(), ec);
    }
    published_ = true;
    return true;
  }
  struct stat st {};
  if (::lstat(dir_.c_str(), &st) != 0) {
    if (::rename(staging_.c_str(), dir_.c_str()) != 0) {
      if (err) *err = dir_ + ": cannot move the frames into place: " + errnoText();
      return false;
    }
    staging_.clear();
  } else {
    // One step: after it DIR holds the new frames and the staging path the old ones.
    if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, dir_.c_str(), RENAME_EXCHANGE) != 0) {
      if (errno != EINVAL && errno != ENOSYS) {
        if (err) *err = dir_ + ": cannot swap the new frames in: " + errnoText();
        return false;
      }
      // A file system without RENAME_EXCHANGE: two renames; the old frames wait under a staging
      // name (removed by the next run should this one be killed in between).
      const std::string old = staging_ + "-old";
      if (::rename(dir_.c_str(), old.c_str()) != 0 || ::rename(staging_.c_str(), dir_.c_str()) != 0) {
        if (err) *err = dir_ + ": cannot move the new frames in: " + errnoText();
        ::rename(old.c_str(), dir_.c_str());
        return false;
      }
      fs::remove_all(old, ec);
    }
    fs::remove_all(staging_, ec);
    staging_.clear();
  }
  published_ = true;
  return true;
}

// --- InterruptGuard ----------------------------------------------------------------------------

InterruptGuard::InterruptGuard() {
  g_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART | SA_RESETHAND;  // a second signal: the default action (exit now)
  sigaction(SIGINT, &sa, &g_old_int);
  sigaction(SIGTERM, &sa, &g_old_term);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
}

int InterruptGuard::signal() { return g_signal; }

}  // namespace ponyhop

#include "sim/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace ponyhop {

std::string byteSize(size_t bytes) {
  char buf[48];
  if (bytes >= 1024 * 1024) {
    std::snprintf(buf, sizeof(buf), "%.1f MB (%zu bytes)", double(bytes) / (1024.0 * 1024.0), bytes);
  } else if (bytes >= 1024) {
    std::snprintf(buf, sizeof(buf), "%.0f KB", double(bytes) / 1024.0);
  } else {
    std::snprintf(buf, sizeof(buf), "%zu bytes", bytes);
  }
  return buf;
}

namespace {

bool kindError(const struct stat& st, const std::string& path, const char* what, std::string* err) {
  if (S_ISREG(st.st_mode)) return false;
  const char* kind = S_ISDIR(st.st_mode)                          ? "a folder"
                     : S_ISFIFO(st.st_mode)                       ? "a FIFO (named pipe)"
                     : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                     : S_ISSOCK(st.st_mode)                       ? "a socket"
                                                                  : "not a regular file";
  if (err) *err = path + ": is " + kind + ", not a " + what;
  return true;
}

}  // namespace

bool readInputFile(const std::string& path, size_t max_bytes, const char* what, std::string* out, std::string* err) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (err) *err = path + ": " + (errno == ENOENT ? std::string("no such file") : std::strerror(errno));
    return false;
  }
  if (kindError(st, path, what, err)) return false;
  // O_NONBLOCK: should the path become a FIFO between stat() and open(), open() does not wait.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    if (err) *err = path + ": cannot open the " + what + ": " + std::strerror(errno);
    return false;
  }
  bool ok = ::fstat(fd, &st) == 0 && !kindError(st, path, what, err);
  if (ok && static_cast<unsigned long long>(st.st_size) > max_bytes) {
    if (err) {
      *err = path + ": the " + what + " is " + byteSize(size_t(st.st_size)) + "; the limit is " + byteSize(max_bytes);
    }
    ok = false;
  }
  std::string data;
  if (ok) {
    data.reserve(size_t(st.st_size));
    char buf[65536];
    for (;;) {
      const ssize_t n = ::read(fd, buf, sizeof(buf));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        if (err) *err = path + ": read failed: " + std::strerror(errno);
        ok = false;
        break;
      }
      if (n == 0) break;
      data.append(buf, size_t(n));
      if (data.size() > max_bytes) {  // the file grew while being read
        if (err) *err = path + ": the " + what + " is larger than the limit of " + byteSize(max_bytes);
        ok = false;
        break;
      }
    }
  }
  ::close(fd);
  if (ok) *out = std::move(data);
  return ok;
}

}  // namespace ponyhop

#include "engine/isolated.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>

#include "physics/stage_times.h"

namespace ponyhop {
namespace {

// Virtual memory of this process now (bytes), from /proc/self/statm; 0 when unknown.
size_t currentVirtualBytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  unsigned long pages = 0;
  const bool ok = std::fscanf(f, "%lu", &pages) == 1;
  std::fclose(f);
  return ok ? size_t(pages) * size_t(sysconf(_SC_PAGESIZE)) : 0;
}

bool writeAll(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= size_t(w);
  }
  return true;
}

[[noreturn]] void childMain(int fd, const std::function<bool(std::string&, std::string&)>& work,
                            const IsolationLimits& limits) {
  // Memory: what the child inherited plus the budget (a fixed cap would fail at once in a large
  // parent, e.g. under AddressSanitizer's reserved shadow).
  const size_t base = currentVirtualBytes();
  if (base > 0 && limits.memory_bytes > 0) {
    rlimit rl{};
    rl.rlim_cur = rl.rlim_max = rlim_t(base + limits.memory_bytes);
    setrlimit(RLIMIT_AS, &rl);
  }
  rlimit core{};  // a crash here is expected and reported; no core file
  setrlimit(RLIMIT_CORE, &core);
  // The default action for every signal the parent may handle: SIGINT/SIGTERM must end the
  // child, and a crash must end it as a crash (not in a handler of the parent's, such as a
  // sanitizer's or libFuzzer's, which would report the importer's crash as the parent's).
  for (const int sig : {SIGINT, SIGTERM, SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT}) signal(sig, SIG_DFL);
  std::string result, error;
  bool ok = false;
  try {
    ok = work(result, error);
  } catch (const std::bad_alloc&) {
    error = "ran out of its memory limit of " + std::to_string(limits.memory_bytes >> 20) + " MB";
  } catch (const std::exception& e) {
    error = e.what();
  } catch (...) {
    error = "unknown exception";
  }
  const std::string& payload = ok ? result : error;
  const uint8_t status = ok ? 1 : 0;
  const uint64_t size = payload.size();
  const bool sent =
      writeAll(fd, &status, 1) && writeAll(fd, &size, sizeof(size)) && writeAll(fd, payload.data(), payload.size());
  ::close(fd);
  _exit(sent ? 0 : 3);  // no atexit handlers, no destructors of the parent's objects
}

}  // namespace

IsolationLimits importLimits() {
  IsolationLimits l;
  if (const char* s = std::getenv("PONYHOP_IMPORT_TIMEOUT")) {
    const double v = std::atof(s);
    if (v > 0.0) l.seconds = v;
  }
  return l;
}

bool runIsolated(const std::function<bool(std::string&, std::string&)>& work, const IsolationLimits& limits,
                 std::string* result, std::string* error) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    if (error) *error = std::string("cannot create a pipe: ") + std::strerror(errno);
    return false;
  }
  std::fflush(nullptr);  // buffered output must not be written twice
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    if (error) *error = std::string("cannot start the import process: ") + std::strerror(errno);
    return false;
  }
  if (pid == 0) {
    ::close(fds[0]);
    childMain(fds[1], work, limits);
  }
  ::close(fds[1]);

  const auto deadline = Clock::now() + std::chrono::duration<double>(limits.seconds);
  std::string data;
  bool timed_out = false;
  for (;;) {
    const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
    if (left <= 0.0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int r = ::poll(&p, 1, int(std::min(left * 1000.0, 1000.0)) + 1);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) break;
    if (r == 0) continue;
    char buf[65536];
    const ssize_t n = ::read(fds[0], buf, sizeof(buf));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // EOF: the child closed its end (finished or died)
    data.append(buf, size_t(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  int wstatus = 0;
  while (::waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "took longer than %.0f s and was stopped", limits.seconds);
    if (error) *error = buf;
    return false;
  }
  if (WIFSIGNALED(wstatus)) {
    const int sig = WTERMSIG(wstatus);
    const char* name = sigabbrev_np(sig);
    if (error) {
      *error = "crashed with SIG" + std::string(name ? name : std::to_string(sig)) +
               (sig == SIGXCPU ? " (CPU time limit)" : "") + " while reading the file";
    }
    return false;
  }
  const size_t header = 1 + sizeof(uint64_t);
  uint64_t size = 0;
  if (data.size() >= header) std::memcpy(&size, data.data() + 1, sizeof(size));
  if (data.size() < header || data.size() - header != size) {
    if (error) *error = "stopped without an answer (exit status " + std::to_string(WEXITSTATUS(wstatus)) + ")";
    return false;
  }
  std::string payload = data.substr(header);
  if (data[0] != 1) {
    if (error) *error = std::move(payload);
    return false;
  }
  if (result) *result = std::move(payload);
  return true;
}

}  // namespace ponyhop

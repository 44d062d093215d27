#include "engine/video.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

namespace ponyhop {

namespace {

struct RunResult {
  bool started = false;
  int exit_code = -1;
  std::string output;  // stdout + stderr
};

// Runs argv[0] (searched in PATH) without a shell; collects its output.
RunResult run(const std::vector<std::string>& args) {
  RunResult r;
  int fds[2];
  if (pipe(fds) != 0) return r;
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    return r;
  }
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    const int devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) dup2(devnull, STDIN_FILENO);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    _exit(127);  // exec failed: program not found
  }
  close(fds[1]);
  char buf[4096];
  for (;;) {
    const ssize_t n = read(fds[0], buf, sizeof(buf));
    if (n > 0) {
      r.output.append(buf, size_t(n));
      if (r.output.size() > (1u << 20)) r.output.erase(0, r.output.size() - (1u << 19));  // keep the tail
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  r.started = r.exit_code != 127;
  return r;
}

std::string tail(const std::string& s, size_t lines) {
  size_t pos = s.size();
  while (pos > 0 && (s[pos - 1] == '\n' || s[pos - 1] == '\r')) --pos;
  size_t end = pos;
  for (size_t k = 0; k < lines && pos > 0; ++k) {
    pos = s.rfind('\n', pos - 1);
    if (pos == std::string::npos) {
      pos = 0;
      break;
    }
  }
  return s.substr(pos == 0 ? 0 : pos + 1, end - (pos == 0 ? 0 : pos + 1));
}

}  // namespace

bool ffmpegAvailable(const std::string& ffmpeg) {
  const RunResult r = run({ffmpeg, "-hide_banner", "-version"});
  return r.started && r.exit_code == 0;
}

std::string videoContainer(const std::string& path, std::string* err) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".mp4" || ext == ".mov" || ext == ".webm" || ext == ".gif") return ext.substr(1);
  if (err) {
    *err = path + ": cannot tell the video container from \"" + ext +
           "\": name the file .mp4 or .mov (H.264), .webm (VP9) or .gif";
  }
  return "";
}

bool encodeVideo(const std::string& frame_dir, const std::string& out_mp4, const VideoOptions& opt, std::string* err) {
  namespace fs = std::filesystem;
  char first[64];
  std::snprintf(first, sizeof(first), opt.pattern.c_str(), opt.start_number);
  if (!fs::exists(fs::path(frame_dir) / first)) {
    if (err) *err = frame_dir + ": no first frame " + first + " to encode";
    return false;
  }
  if (!(opt.fps > 0.0)) {
    if (err) *err = "encodeVideo: fps must be > 0";
    return false;
  }
  // A caller writing under a temporary name gives the container of the final name.
  const std::string container = opt.container.empty() ? videoContainer(out_mp4, err) : opt.container;
  if (container.empty()) return false;
  std::error_code ec;
  if (fs::path(out_mp4).has_parent_path()) fs::create_directories(fs::path(out_mp4).parent_path(), ec);
  const std::string tmp = out_mp4 + ".tmp";
  char fps[32];
  std::snprintf(fps, sizeof(fps), "%.6g", opt.fps);
  std::vector<std::string> args = {
      opt.ffmpeg, "-hide_banner", "-loglevel", "error", "-y", "-framerate", fps, "-start_number",
      std::to_string(opt.start_number), "-i", (fs::path(frame_dir) / opt.pattern).string()};
  // yuv420p needs even sizes: pad odd ones by a pixel (of the edge colour would need a filter
  // graph; black padding of one pixel is invisible in players).
  const std::string pad = "pad=ceil(iw/2)*2:ceil(ih/2)*2";
  if (container == "mp4" || container == "mov") {
    args.insert(args.end(), {"-vf", pad, "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", std::to_string(opt.crf),
                             "-movflags", "+faststart"});
  } else if (container == "webm") {
    // VP9 at constant quality; yuva420p keeps a transparent background's alpha.
    args.insert(args.end(), {"-vf", pad, "-c:v", "libvpx-vp9", "-pix_fmt", "yuva420p", "-crf", "32", "-b:v", "0",
                             "-deadline", "good", "-cpu-used", "4", "-row-mt", "1"});
  } else {  // gif: one palette made for the whole video
    args.insert(args.end(), {"-vf", "split[a][b];[a]palettegen=reserve_transparent=1[p];[b][p]paletteuse", "-loop", "0"});
  }
  args.insert(args.end(), {"-f", container, tmp});
  const RunResult r = run(args);
  if (!r.started) {
    if (err) *err = "encodeVideo: cannot run '" + opt.ffmpeg + "' (install the ffmpeg package)";
    return false;
  }
  if (r.exit_code != 0) {
    fs::remove(tmp, ec);
    if (err)
      *err = out_mp4 + ": ffmpeg failed (exit " + std::to_string(r.exit_code) + "):\n" + tail(r.output, 12);
    return false;
  }
  fs::rename(tmp, out_mp4, ec);
  if (ec) {
    if (err) *err = out_mp4 + ": cannot rename " + tmp + " (" + ec.message() + ")";
    fs::remove(tmp, ec);
    return false;
  }
  return true;
}

}  // namespace ponyhop

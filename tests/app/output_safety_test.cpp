// Faults a run must survive without losing output (docs/RELIABILITY.md): SIGINT and SIGTERM sent
// to a rendering child, SIGKILL and the next run, two renders into one folder, a full disk
// (RLIMIT_FSIZE), outputs that are inputs or devices, values CLI11 would let through.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <thread>

#include "common/run_util.h"
#include "engine/image.h"

namespace ponyhop {
namespace {

namespace fs = std::filesystem;
using testing::readFile;
using testing::runPonyhop;
using testing::scratch;
using testing::writeFile;

// A ponyhop child we can signal. Output goes to LOG; `fsize` > 0 limits the size of any file it
// writes (RLIMIT_FSIZE: a full disk, as seen by write(2)).
// With a size limit the output goes through a pipe (the limit would cut a log file short).
struct Child {
  pid_t pid = -1;
  std::string log;
  int pipe_fd = -1;

  Child(const std::vector<std::string>& args, const std::string& log_path, rlim_t fsize = 0) : log(log_path) {
    int fds[2] = {-1, -1};
    if (fsize > 0 && pipe(fds) != 0) return;
    pid = fork();
    if (pid == 0) {
      const int fd = fsize > 0 ? fds[1] : open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      if (fsize > 0) {
        rlimit rl{fsize, fsize};
        setrlimit(RLIMIT_FSIZE, &rl);
      }
      std::vector<char*> argv{const_cast<char*>(PONYHOP_EXE)};
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(PONYHOP_EXE, argv.data());
      _exit(127);
    }
    if (fsize > 0) {
      close(fds[1]);
      pipe_fd = fds[0];
    }
  }
  // Exit code, or 128 + signal when killed by one.
  int wait() {
    if (pipe_fd >= 0) {
      std::string text;
      char buf[4096];
      ssize_t n;
      while ((n = read(pipe_fd, buf, sizeof(buf))) > 0) text.append(buf, size_t(n));
      close(pipe_fd);
      pipe_fd = -1;
      writeFile(log, text);
    }
    int st = 0;
    waitpid(pid, &st, 0);
    pid = -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  }
  ~Child() {
    if (pid > 0) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
  }
  std::string output() const { return readFile(log); }
};

int countFrames(const std::string& dir) {
  int n = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().filename().string().rfind("frame_", 0) == 0) ++n;
  }
  return n;
}

// The staging folders beside DIR (DIR.partial-PID).
std::vector<std::string> stagingOf(const std::string& dir) {
  std::vector<std::string> out;
  const std::string prefix = fs::path(dir).filename().string() + ".partial-";
  for (const auto& e : fs::directory_iterator(fs::path(dir).parent_path())) {
    if (e.path().filename().string().rfind(prefix, 0) == 0) out.push_back(e.path().string());
  }
  return out;
}

// Waits until the child has staged at least one frame (it is rendering), at most 120 s.
bool waitForStagedFrame(const std::string& dir) {
  for (int i = 0; i < 1200; ++i) {
    for (const auto& s : stagingOf(dir)) {
      if (fs::exists(s + "/frame_00000.png")) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

// A long render (small frames, many of them) into OUT.
std::vector<std::string> longRender(const std::string& out) {
  return {"render", "assets/scenes/chain.json", "--frames", "100000", "--size", "64x48",
          "--set",  "render.samples=1",         "--out",    out};
}

// OUT with two frames from an earlier run whose bytes we can recognise.
void previousOutput(const std::string& out) {
  writeFile(out + "/frame_00000.png", "previous 0");
  writeFile(out + "/frame_00001.png", "previous 1");
}
void expectPreviousOutput(const std::string& out) {
  EXPECT_EQ(readFile(out + "/frame_00000.png"), "previous 0");
  EXPECT_EQ(readFile(out + "/frame_00001.png"), "previous 1");
  EXPECT_EQ(countFrames(out), 2);
  EXPECT_TRUE(stagingOf(out).empty()) << "staging left: " << stagingOf(out).front();
  EXPECT_FALSE(fs::exists(out + ".lock"));
}

TEST(OutputSafety, SigintAndSigtermStopARenderCleanly) {
  for (const int sig : {SIGINT, SIGTERM}) {
    const std::string dir = scratch(std::string("signal_") + std::to_string(sig));
    const std::string out = dir + "/out";
    previousOutput(out);
    Child c(longRender(out), dir + "/log.txt");
    ASSERT_TRUE(waitForStagedFrame(out)) << c.output();
    kill(c.pid, sig);
    EXPECT_EQ(c.wait(), 128 + sig) << c.output();
    EXPECT_NE(c.output().find(sig == SIGINT ? "stopped by SIGINT" : "stopped by SIGTERM"), std::string::npos)
        << c.output();
    expectPreviousOutput(out);
  }
}

// `sim` too: a long run's CSV (--csv) or pose file (--poses) is written under FILE.partial-PID;
// SIGINT or SIGTERM removes it and leaves the previous file as it was.
TEST(OutputSafety, SigintAndSigtermStopASimCleanly) {
  for (const std::string flag : {"--csv", "--poses"}) {
    for (const int sig : {SIGINT, SIGTERM}) {
      const std::string dir = scratch("sim_signal_" + flag.substr(2) + "_" + std::to_string(sig));
      const std::string out = dir + "/out.csv";
      writeFile(out, "previous");
      Child c({"sim", "assets/scenes/chain.json", "--duration", "100000", flag, out}, dir + "/log.txt");
      const std::string partial = out + ".partial-" + std::to_string(c.pid);
      bool started = false;  // rows are being written
      for (int i = 0; i < 1200 && !started; ++i) {
        std::error_code ec;
        started = fs::exists(partial) && fs::file_size(partial, ec) > 1000;
        if (!started) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      ASSERT_TRUE(started) << flag << ": no " << partial << "\n" << c.output();
      kill(c.pid, sig);
      EXPECT_EQ(c.wait(), 128 + sig) << flag << "\n" << c.output();
      EXPECT_NE(c.output().find(sig == SIGINT ? "stopped by SIGINT" : "stopped by SIGTERM"), std::string::npos)
          << c.output();
      EXPECT_EQ(readFile(out), "previous") << flag;
      EXPECT_FALSE(fs::exists(partial)) << flag << ": " << partial << " left behind";
    }
  }
}

TEST(OutputSafety, NextRunCleansWhatASigkilledRunLeft) {
  const std::string dir = scratch("sigkill");
  const std::string out = dir + "/out";
  previousOutput(out);
  {
    Child c(longRender(out), dir + "/log.txt");
    ASSERT_TRUE(waitForStagedFrame(out)) << c.output();
    kill(c.pid, SIGKILL);
    c.wait();
  }
  ASSERT_EQ(stagingOf(out).size(), 1u) << "a killed run leaves its staging folder";
  EXPECT_EQ(readFile(out + "/frame_00000.png"), "previous 0") << "the kill must not touch the output";
  const auto r = runPonyhop("render assets/scenes/chain.json --frames 3 --size 64x48 --out " + out, "after_kill");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(stagingOf(out).empty()) << "the next run removes stale staging folders";
  EXPECT_EQ(countFrames(out), 3);
  EXPECT_FALSE(loadPng(out + "/frame_00002.png").empty());
}

TEST(OutputSafety, SecondRenderIntoTheSameFolderIsRefusedNamingTheHolder) {
  const std::string dir = scratch("concurrent");
  const std::string out = dir + "/out";
  previousOutput(out);
  Child a(longRender(out), dir + "/a.txt");
  ASSERT_TRUE(waitForStagedFrame(out)) << a.output();
  const auto b = runPonyhop("render assets/scenes/chain.json --frames 3 --size 64x48 --out " + out, "concurrent_b");
  EXPECT_EQ(b.code, 2) << b.out;
  EXPECT_NE(b.out.find("another render is writing this folder"), std::string::npos) << b.out;
  EXPECT_NE(b.out.find("pid " + std::to_string(a.pid)), std::string::npos) << b.out;
  EXPECT_EQ(readFile(out + "/frame_00000.png"), "previous 0");
  kill(a.pid, SIGTERM);
  EXPECT_EQ(a.wait(), 143) << a.output();
  expectPreviousOutput(out);
}

TEST(OutputSafety, FullDiskFailsClearlyAndKeepsThePreviousOutput) {
  const std::string dir = scratch("full_disk");
  const std::string out = dir + "/out";
  previousOutput(out);
  // 2 KB per file: the log fits, a 320x240 frame does not.
  Child c({"render", "assets/scenes/chain.json", "--frames", "5", "--size", "320x240", "--out", out}, dir + "/log.txt",
          2048);
  EXPECT_EQ(c.wait(), 1) << c.output();
  EXPECT_NE(c.output().find("File too large"), std::string::npos) << c.output();
  EXPECT_NE(c.output().find("is untouched"), std::string::npos) << c.output();
  expectPreviousOutput(out);

  // diff --out on a full disk: exit 2, not PASS with an empty file.
  Image img(8, 8, 200, 10, 10);
  ASSERT_TRUE(savePng(dir + "/a.png", img));
  Child d({"diff", dir + "/a.png", dir + "/a.png", "--out", dir + "/d.png"}, dir + "/diff_log.txt", 40);
  EXPECT_EQ(d.wait(), 2) << d.output();
  EXPECT_NE(d.output().find("d.png"), std::string::npos) << d.output();
  EXPECT_FALSE(fs::exists(dir + "/d.png"));
}

TEST(OutputSafety, VideoToAnUnwritablePlaceFailsBeforeRendering) {
  const std::string dir = scratch("video_unwritable");
  const std::string out = dir + "/out";
  previousOutput(out);
  writeFile(dir + "/a_file", "x");
  const auto r = runPonyhop(
      "render assets/scenes/chain.json --frames 3 --size 64x48 --out " + out + " --video " + dir + "/a_file/v.mp4",
      "video_unwritable");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--video"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("render: frame"), std::string::npos) << "rendered before failing:\n" << r.out;
  expectPreviousOutput(out);
}

TEST(OutputSafety, OutputsThatAreInputsOrDevicesAreRefused) {
  const std::string dir = scratch("outputs");
  const std::string out = dir + "/out";
  previousOutput(out);
  fs::copy_file("assets/scenes/chain.json", dir + "/scene.json");
  const std::string scene_text = readFile(dir + "/scene.json");
  Image img(8, 8, 200, 10, 10);
  ASSERT_TRUE(savePng(dir + "/golden.png", img));
  ASSERT_TRUE(savePng(dir + "/actual.png", Image(8, 8, 10, 200, 10)));
  const std::string golden = readFile(dir + "/golden.png");
  const std::string render = "render " + dir + "/scene.json --frames 2 --size 64x48 --out " + out;
  struct Case {
    std::string args, expect;
  } cases[] = {
      {render + " --video " + out + "/frame_00000.png", "inside the frames folder"},
      {render + " --video " + dir + "/scene.json", "is an input of this run"},
      {render + " --video /dev/null", "is a device"},
      {"diff " + dir + "/golden.png " + dir + "/actual.png --out " + dir + "/golden.png", "is an input of this run"},
      {"diff " + dir + "/golden.png " + dir + "/actual.png --out /dev/null", "is a device"},
      {"sim " + dir + "/scene.json --duration 0.01 --csv /dev/null", "is a device"},
      {"sim " + dir + "/scene.json --duration 0.01 --csv " + dir + "/scene.json", "is an input of this run"},
      {"sim " + dir + "/scene.json --duration 0.01 --csv " + out, "is a folder"},
      {render + " --video ''", "--video"},
      {render + " --size ''", "--size"},
      {"render " + dir + "/scene.json --frames 2 --out ''", "--out"},
      {render + " --fps nan", "--fps"},
      {"sim " + dir + "/scene.json --duration nan --csv " + dir + "/x.csv", "--duration"},
      {"sim " + dir + "/scene.json --duration 0.01 --csv ''", "--csv"},
      {"render " + dir + "/scene.json --frames 2 --size 64x48 --out " + dir, "holds files that are not frames"},
  };
  int n = 0;
  for (const auto& c : cases) {
    const auto r = runPonyhop(c.args, "outputs" + std::to_string(n++));
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << " said:\n" << r.out;
  }
  EXPECT_EQ(readFile(dir + "/scene.json"), scene_text);
  EXPECT_EQ(readFile(dir + "/golden.png"), golden);
  expectPreviousOutput(out);
}

TEST(OutputSafety, FramesAreReplacedWholeAndTheVideoBesideThem) {
  const std::string dir = scratch("replace_whole");
  const std::string out = dir + "/out";
  for (int i = 0; i < 6; ++i) writeFile(out + "/frame_0000" + std::to_string(i) + ".png", "old");
  const auto r = runPonyhop("render assets/scenes/chain.json --frames 3 --size 64x48 --out " + out +
                                (std::system("command -v ffmpeg >/dev/null") == 0 ? " --video " + dir + "/v.mp4" : ""),
                            "replace_whole");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(countFrames(out), 3) << "frames of the older, longer run are gone";
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(loadPng(out + "/frame_0000" + std::to_string(i) + ".png").empty());
  EXPECT_TRUE(stagingOf(out).empty());
  EXPECT_FALSE(fs::exists(out + ".lock"));
  for (const auto& e : fs::directory_iterator(dir)) {
    EXPECT_EQ(e.path().filename().string().find(".partial"), std::string::npos) << e.path();
  }
}

// A small tmpfs (needs CAP_SYS_ADMIN: skipped elsewhere), unmounted when the test ends.
struct Tmpfs {
  std::string path;
  bool ok = false;
  Tmpfs(const std::string& p, const char* size) : path(p) {
    fs::create_directories(p);
    ok = mount("tmpfs", p.c_str(), "tmpfs", 0, size) == 0;
  }
  ~Tmpfs() {
    if (ok) umount2(path.c_str(), MNT_DETACH);
  }
};

TEST(OutputSafety, ARealFullDiskAndAnOutThatIsAMountPoint) {
  const std::string dir = scratch("tmpfs");
  Tmpfs disk(dir + "/disk", "size=256k");
  if (!disk.ok) GTEST_SKIP() << "cannot mount a tmpfs here (not root?): " << std::strerror(errno);
  // Full: 40 frames of 320x240 do not fit in 256 KB beside the previous output.
  const std::string out = dir + "/disk/out";
  previousOutput(out);
  const auto full = runPonyhop("render assets/scenes/chain.json --frames 40 --size 320x240 --out " + out, "tmpfs_full");
  EXPECT_EQ(full.code, 1) << full.out;
  EXPECT_NE(full.out.find("No space left on device"), std::string::npos) << full.out;
  expectPreviousOutput(out);

  // --out is the mount point itself: it cannot be renamed, the frames are moved in one by one.
  Tmpfs mnt(dir + "/mnt", "size=8m");
  ASSERT_TRUE(mnt.ok);
  for (const int frames : {4, 2}) {
    const auto r = runPonyhop(
        "render assets/scenes/chain.json --frames " + std::to_string(frames) + " --size 64x48 --out " + mnt.path,
        "tmpfs_mount" + std::to_string(frames));
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(countFrames(mnt.path), frames);
    EXPECT_FALSE(loadPng(mnt.path + "/frame_00001.png").empty());
    for (const auto& e : fs::directory_iterator(mnt.path)) {
      EXPECT_EQ(e.path().filename().string().find(".partial"), std::string::npos) << e.path();
    }
  }
}

}  // namespace
}  // namespace ponyhop

// Output safety for the commands that write (docs/RELIABILITY.md): every output path is checked
// before work starts; a frame folder is replaced whole, in one step, by a run that succeeded,
// under a lock; SIGINT/SIGTERM stop a run cleanly.
#pragma once

#include <string>
#include <vector>

namespace ponyhop {

struct Scene;

// The files a scene run reads: the scene, its mesh and clip (outputs must not be one of them).
std::vector<std::string> sceneInputs(const Scene& scene);

// True when `a` and `b` name the same file: the same inode when both exist, else the same
// absolute normalized path.
bool samePath(const std::string& a, const std::string& b);

// An output file (video, CSV, diff image): not "", not a folder, FIFO or device, not the same
// file as one of `inputs`; its folder is created when missing and must accept a new file.
// Throws InputError naming `option` and the path.
void checkOutputFile(const std::string& option, const std::string& path, const std::vector<std::string>& inputs);

// The frames of one run. The constructor checks DIR (absent, or a folder holding frames only:
// the whole folder is replaced), takes the lock DIR.lock (a second run into DIR is refused with
// the holder's pid), removes staging folders that killed runs left beside DIR, and creates the
// staging folder (DIR.partial-PID) that the frames are written to. publish() swaps the staging
// folder in for DIR in one rename (renameat2 RENAME_EXCHANGE) and deletes the old frames. The
// destructor removes the staging folder of a run that did not publish and releases the lock.
class FrameFolder {
 public:
  FrameFolder(const std::string& option, const std::string& dir);
  ~FrameFolder();
  FrameFolder(const FrameFolder&) = delete;
  FrameFolder& operator=(const FrameFolder&) = delete;

  const std::string& dir() const { return dir_; }
  const std::string& staging() const { return staging_; }
  // False with *err when the swap failed (DIR is then as it was).
  bool publish(std::string* err);

 private:
  std::string dir_, staging_, lock_path_;
  int lock_fd_ = -1;
  bool mount_point_ = false;  // DIR is a mount point: staged inside it, moved frame by frame
  bool published_ = false;
};

// While alive, SIGINT and SIGTERM set a flag instead of killing the process; the command polls
// signal() (between frames, between steps), cleans up and returns exitCodeFor(signal()). A
// second signal kills at once (the default action is restored when the first arrives).
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static int signal();                                // 0 while none came
  static int exitCode(int sig) { return 128 + sig; }  // 130 for SIGINT, 143 for SIGTERM
};

}  // namespace ponyhop

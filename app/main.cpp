// ponyhop: constrained rigid-body dynamics the way games use it (a ponytail on a keyframed head,
// a Raibert hopper), rendered headless to PNG/video, tuned live in a window, guarded by snapshots.
#include <csignal>

#include "app/commands.h"
#include "bench/commands.h"

int main(int argc, char** argv) {
  // A file size limit (RLIMIT_FSIZE) makes a write fail with EFBIG, reported like a full disk,
  // instead of killing the process with SIGXFSZ halfway through a file.
  std::signal(SIGXFSZ, SIG_IGN);
  // The subcommands in the order `ponyhop --help` lists them: app/'s, the bench's, then `run`.
  return ponyhop::runCommandLine(argc, argv, {ponyhop::benchCommand(), ponyhop::benchRenderCommand()});
}

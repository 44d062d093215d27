// Runs untrusted parsing (assimp on a user's mesh) in a child process with a time and memory
// limit, so that an importer that crashes, aborts, loops or allocates without end takes only the
// child down; the parent gets a message instead (docs/RELIABILITY.md).
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace ponyhop {

struct IsolationLimits {
  double seconds = 30.0;                  // wall-clock time, then the child is killed
  size_t memory_bytes = size_t(1) << 30;  // address space the child may add to what it inherits
};

// Forks; the child runs `work`, which fills `result` (any bytes) or `error` and returns success;
// the parent returns the same. When the child crashes, is killed or exceeds a limit, returns
// false with *error saying which ("crashed with SIGSEGV", "took longer than 30 s", ...).
// `work` must not touch threads or GL state of the parent (only the calling thread lives on in
// the child).
bool runIsolated(const std::function<bool(std::string& result, std::string& error)>& work,
                 const IsolationLimits& limits, std::string* result, std::string* error);

// Limits used for mesh and animation import. PONYHOP_IMPORT_TIMEOUT (seconds) overrides the time
// limit (tests use a short one).
IsolationLimits importLimits();

}  // namespace ponyhop

#include "app/commands.h"

#include <cstdio>

#include "sim/input_error.h"

namespace ponyhop {

int runCommand(const char* name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::fprintf(stderr, "ponyhop %s: %s\n", name, e.what());
    return 2;
  }
}

}  // namespace ponyhop

// A user's bad input: a scene file or `--set` (the message names the file or option, the key and
// what is allowed), a clip, a preset, a shot list, an output path (`--csv`, `--poses`, `--out`), an
// option's value (`--sizes`, `--range`, an export's extension). The commands print what() after
// their name and exit with 2 (app/commands.h, runCommand).
#pragma once

#include <stdexcept>

namespace ponyhop {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace ponyhop

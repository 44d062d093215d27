// Where ponyhop's own files are (assets/scenes, assets/head, assets/animations), found relative to
// the running executable, never a path compiled in: an installed ponyhop (PREFIX/bin/ponyhop)
// reads PREFIX/share/ponyhop/assets; one in a build folder reads BUILD/share/ponyhop/assets (a
// link to the source tree's assets/ that CMake makes). PONYHOP_DATA_DIR overrides both.
#pragma once

#include <string>

namespace ponyhop {

// The folder holding assets/ ("" when none is found).
const std::string& dataDir();

// A scene named on the command line: the path as given (relative to the working directory),
// else the same path under dataDir() (e.g. assets/scenes/ponytail.json), else a bare name under
// dataDir()/assets/scenes (e.g. "ponytail"). Returns the path unchanged when none exists, so the
// error names what the user typed.
std::string resolveSceneFile(const std::string& path);

// The version of this build ("0.9.0").
const char* versionString();

}  // namespace ponyhop

// Head grids kept as files between runs (physics/models/head_collisions.h, GridStore).
//
// Building the default head's distance grid costs about 0.6 s of CPU, and every process that makes
// a head collider pays it: each chunk of a render farm, each `ponyhop render` of an edit, each test.
// When the environment variable PONYHOP_GRID_CACHE names a folder, a grid once built is written
// there (grid-<key>.bin) and every later process with the same head, cell and region reads it back
// instead (a few milliseconds). The key covers the builder's own code, so a file from another build
// of ponyhop is never taken; a file that is short, corrupted or of another key is ignored and
// written anew. The folder is made when missing; when it cannot be written, grids are built as
// without it. `make test` points it at the build folder (tests/CMakeLists.txt).
#pragma once

#include <memory>
#include <string>

#include "physics/models/head_collisions.h"

namespace ponyhop {

// A store of grids as files in `folder`.
std::shared_ptr<const GridStore> fileGridStore(std::string folder);

// Installs fileGridStore(PONYHOP_GRID_CACHE) for this process when the variable names a folder.
// Once per process; every Sim's constructor calls it.
void useGridCacheFromEnvironment();

}  // namespace ponyhop

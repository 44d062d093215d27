// Reading an input file whole, safely: only a regular file (a folder, FIFO, device or socket is
// refused before it is opened, so nothing blocks), never more than a stated size.
#pragma once

#include <cstddef>
#include <string>

namespace ponyhop {

// Reads `path` into *out. False with *err = "PATH: reason" (no such file, a folder, not a regular
// file, larger than `max_bytes` with the limit named, a read error). `what` names the file's
// role in messages ("scene file", "PNG", ...).
bool readInputFile(const std::string& path, size_t max_bytes, const char* what, std::string* out, std::string* err);

// "12.0 MB", "512 KB", "900 bytes": sizes in messages.
std::string byteSize(size_t bytes);

}  // namespace ponyhop

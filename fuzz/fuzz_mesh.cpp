// libFuzzer target: mesh import as ponyhop does it (engine/mesh: assimp in a child process with
// a time and memory limit, then the checks of what comes back). The first byte picks the file
// type (the importer is chosen by extension); the rest is the file. assimp's own crashes and
// hangs happen in the child and must come back as messages: this process must never crash.
// (Coverage inside the child does not reach libFuzzer, so this target checks survival and the
// parent's checks rather than exploring assimp.)
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "engine/mesh.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  setenv("PONYHOP_IMPORT_TIMEOUT", "3", 0);  // a hang costs 3 s, not 30
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kExt[] = {"ply", "obj", "stl", "gltf", "glb", "off", "dae", "fbx"};
  const std::string path = "/tmp/ponyhop_fuzz_mesh_" + std::to_string(getpid()) + "." + kExt[data[0] % 8];
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data + 1, 1, size - 1, f);
  std::fclose(f);
  ponyhop::MeshData mesh;
  std::string err;
  if (ponyhop::loadMesh(path, mesh, &err)) {
    for (uint32_t i : mesh.indices) {
      if (i >= mesh.positions.size()) __builtin_trap();
    }
    if (mesh.normals.size() != mesh.positions.size()) __builtin_trap();
  } else if (err.empty()) {
    __builtin_trap();  // a failure must say why
  }
  std::remove(path.c_str());
  return 0;
}

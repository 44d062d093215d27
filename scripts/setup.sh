#!/usr/bin/env bash
# Installs the Debian packages ponyhop needs, and only those that are missing.
# Idempotent: a machine that has everything runs no apt command at all.
#   scripts/setup.sh           what `make demo` and `make test` need
#   scripts/setup.sh --bench   also the peer engines `ponyhop bench` compares against (`make bench`)
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config     # toolchain
  ninja-build                          # builds (make picks Ninja for a new build folder when it is there)
  libeigen3-dev                        # physics: dense and sparse linear algebra
  libosmesa6-dev                       # headless OpenGL (Mesa llvmpipe)
  python3-glad                         # generates the GL loader at build time (offline, --reproducible)
  libassimp-dev                        # mesh and animation import
  libmeshoptimizer-dev                 # simplified shadow casters of large meshes (engine/mesh_upload.cpp)
  libimgui-dev libstb-dev              # tuning panel; PNG reading/writing (stb_image, stb_image_write)
  zlib1g-dev                           # fast deflate for PNG frames
  libglfw3-dev                         # the window of `ponyhop run`
  nlohmann-json3-dev                   # scene files
  libcli11-dev                         # command line
  libgtest-dev                         # tests (speed is measured by `ponyhop bench`)
  ffmpeg                               # --video: H.264, VP9 and GIF encoding
  parallel                             # the render-farm test (GNU parallel; docs/RENDER_FARM.md)
  assimp-testmodels                    # third-party heads for the head-placement tests
  gnuplot-nox                          # bench plots
  xvfb xauth                           # window tests without a display
  xdotool                              # the window test moves the mouse and presses keys in Xvfb
)

# The sanitizer trees only (scripts/setup.sh --clang: `make test-asan`, `make test-tsan`, `make fuzz`):
# clang, and its runtime libraries for ASan, UBSan, TSan and libFuzzer.
if [ "${1:-}" = "--clang" ]; then
  PACKAGES+=(clang libclang-rt-14-dev)
fi
# `make format-check` only (scripts/setup.sh --format).
if [ "${1:-}" = "--format" ]; then
  PACKAGES+=(clang-format)
fi
# `make bench` only (scripts/setup.sh --bench): the peer engines the bench compares against
# (bench/peer.h), each optional: configure builds a module for each one found (bench/CMakeLists.txt):
# MuJoCo, Bullet (its -float64 libraries: btMultiBody in double precision), ODE (double), DART.
if [ "${1:-}" = "--bench" ]; then
  PACKAGES+=(libmujoco-dev libbullet-dev libode-dev libdart-dev)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  [[ "$p" == \#* ]] && continue
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "setup: installing missing Debian packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done" >&2

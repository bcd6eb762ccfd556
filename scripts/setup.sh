#!/usr/bin/env bash
# Brings a Debian 12 machine to a built softbake: installs the Debian packages that are missing,
# configures and builds (Release, ./build). Safe to run again; it only does what is left to do.
#   --fuzz-tools         also install clang and libFuzzer (scripts/fuzz.sh)
#   --packages-only      install what is missing, then stop: no configure, no build
#   SOFTBAKE_BUILD_DIR   build folder (default: build)
#   SOFTBAKE_CMAKE_ARGS  extra arguments for the CMake configure step
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

fuzz_tools=false packages_only=false
for argument in "$@"; do
  case "$argument" in
    --fuzz-tools) fuzz_tools=true ;;
    --packages-only) packages_only=true ;;
    *) echo "setup: unknown argument '$argument'" >&2; exit 2 ;;
  esac
done

packages=(
  g++ make cmake pkg-config            # a fresh Debian has no compiler; cmake only recommends make
  libeigen3-dev libtbb-dev             # core
  libassimp-dev nlohmann-json3-dev     # importers
  libopenvdb-dev libboost-iostreams-dev  # exporters (Debian's FindOpenVDB needs boost-iostreams)
  libegl-dev libgl-dev libopengl-dev   # render: the GL and EGL link libraries (FindOpenGL needs libOpenGL)
  libegl-mesa0 libgl1-mesa-dri libstb-dev  # render: EGL on Mesa's llvmpipe
  zlib1g-dev                           # render: PNG deflate; output: the cache files' CRC-32
  libssl-dev                           # output: SHA-256 of a run's input files, in its manifest
  libcli11-dev                         # cli
  libopenimageio-dev                   # cli: compare reads PNG, EXR and TIFF, Yee's metric
  libgtest-dev libgmock-dev libbenchmark-dev  # tests and benchmarks
  libcgal-dev                          # tests: exact triangle–triangle intersection (the checker)
  libbullet-dev                        # the peer benchmark (Bullet btSoftBody)
  pybind11-dev python3-dev             # python/: the module softbake, for Debian's python3 (3.11)
  python3-numpy python3-pytest         # python/: its arrays, and its tests (ctest python_tests)
  chromium                             # tests: compare's HTML report opened headless, offline
)
if $fuzz_tools; then
  # libFuzzer ships in clang's runtime package; llvm gives llvm-symbolizer, so a finding's stack
  # has function names and lines.
  packages+=(clang libclang-rt-14-dev llvm)
fi
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
    missing+=("$package")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "setup: run as root or install sudo" >&2; exit 1; }
    sudo=sudo
  fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

$packages_only && exit 0

build_dir=${SOFTBAKE_BUILD_DIR:-build}
[ -f "$build_dir/CMakeCache.txt" ] || echo "setup: configuring and building in $build_dir (the first build takes a few minutes)" >&2
# shellcheck disable=SC2086  # the extra arguments are meant to split
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release ${SOFTBAKE_CMAKE_ARGS:-} >/dev/null
cmake --build "$build_dir" -j"$(nproc)"

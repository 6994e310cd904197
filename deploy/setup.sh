#!/usr/bin/env bash
# Sets up manisweep on Debian 12: installs exactly the Debian packages it needs (quick when
# they are already there) and builds it (Release, all cores) into build/.
#
#   deploy/setup.sh                 install packages + build
#   deploy/setup.sh --no-build      install packages only
#   BUILD_DIR=... BUILD_TYPE=...    override build/ and Release
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config git clang-format
  # libraries
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libeigen3-dev libopencv-dev
  libzmq3-dev cppzmq-dev libprotobuf-dev protobuf-compiler libhdf5-dev hdf5-tools
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libsqlite3-dev
  # tests, benchmarks, fuzzing
  libgtest-dev libgmock-dev libbenchmark-dev clang libclang-rt-14-dev
  # independent tools: mesh reader + Poisson baseline, SfM for camera-only datasets, cluster
  python3 python3-numpy python3-open3d python3-pil colmap slurm-wlm
  # the run report's browser test
  chromium
  # benchmark plots (bench/scalability)
  python3-matplotlib
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all ${#PACKAGES[@]} Debian packages present"
fi

[ "${1:-}" = "--no-build" ] && exit 0

BUILD_DIR=${BUILD_DIR:-build}
BUILD_TYPE=${BUILD_TYPE:-Release}
export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE="$BUILD_TYPE" ${CMAKE_ARGS:-} >/dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)"
echo "setup: built $BUILD_DIR/app/manisweep"

#!/usr/bin/env bash
# Installs what is missing (Debian 12, as root), then configures and builds freqlab in build/.
# Safe to run again: apt-get runs only when a package is absent, the build is incremental.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake pkg-config
  libembree-dev libopenexr-dev libimath-dev libopenimageio-dev libglm-dev libglfw3-dev libosmesa6-dev
  libimgui-dev libfftw3-dev libtbb-dev nlohmann-json3-dev libassimp-dev libgtest-dev
  libbenchmark-dev libboost-math-dev libopenvdb-dev libblosc-dev libcli11-dev python3-glad xvfb xauth
  blender-data assimp-testmodels fonts-dejavu-core clang-format clang libclang-rt-14-dev
  libopenmpi-dev openmpi-bin
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: these Debian packages are missing and installing them needs root: ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$jobs"

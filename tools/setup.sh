#!/usr/bin/env bash
# Install the Debian packages PE-JUMP needs, fetch LAMMPS (4 Feb 2025) and
# build lmp, liblammps, the plugin and the tests into ./build
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO=sudo
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends build-essential cmake ninja-build ccache \
  libopenmpi-dev openmpi-bin libgtest-dev googletest libyaml-dev python3 python3-numpy \
  python3-matplotlib python3-scipy xz-utils ca-certificates dpkg-dev \
  python3-sphinx python3-sphinxcontrib.spelling hunspell-en-us >/dev/null
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
cmake -S . -B build -G Ninja -D CMAKE_BUILD_TYPE=Release
cmake --build build -j "$(nproc)"

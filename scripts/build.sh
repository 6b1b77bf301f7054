#!/usr/bin/env bash
# Configures and builds ctsurg (Release, Ninja) into build/ using the 'release' CMake preset.
# Extra arguments go to the configure step, e.g. scripts/build.sh -DCTSURG_CUDA=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release "$@" >/dev/null
cmake --build --preset release

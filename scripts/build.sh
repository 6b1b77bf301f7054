#!/usr/bin/env bash
# Configures and builds ctsurg (Release, Ninja) into build/ using the 'release' CMake preset.
#   scripts/build.sh [--tools] [configure arguments...]
# --tools builds the command-line tools only (target ctsurg_tools: what the pipeline and the demo run),
# not the tests and benchmarks. Other arguments go to the configure step, e.g. -DCTSURG_CUDA=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
target=()
if [[ "${1:-}" == "--tools" ]]; then
  target=(--target ctsurg_tools)
  shift
fi
cmake --preset release "$@" >/dev/null
cmake --build --preset release "${target[@]}"

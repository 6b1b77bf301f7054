#!/usr/bin/env bash
# Configures and builds ctsurg (Release, Ninja) into build/ using the 'release' CMake preset.
#   scripts/build.sh [--tools | --tests] [configure arguments...]
# --tools builds the command-line tools only (target ctsurg_tools: what the pipeline and the demo run),
# not the tests and benchmarks; --tests the tools and the test programs (ctsurg_tests: what the suite
# runs), not the benchmarks. Without either, everything. Other arguments go to the configure step,
# e.g. -DCTSURG_CUDA=OFF.
set -euo pipefail
cd "$(dirname "$0")/.."
target=()
if [[ "${1:-}" == "--tools" ]]; then
  target=(--target ctsurg_tools)
  shift
elif [[ "${1:-}" == "--tests" ]]; then
  target=(--target ctsurg_tools ctsurg_tests)
  shift
fi
cmake --preset release "$@" >/dev/null
cmake --build --preset release "${target[@]}"

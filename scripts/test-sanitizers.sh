#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (the 'asan' CMake preset: its
# own build in build-asan/, CUDA off, less two slow tests that the release suite runs). It does not fit
# beside the release suite in CI's 25 minutes on 2 cores, so it runs before a change lands
# (docs/architecture.md, "Build time and CI"); CI fuzzes every file reader under the same sanitizers.
# CTSURG_TEST_ARGS passes extra arguments to ctest (e.g. "-L unit").
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake --preset asan >/dev/null
cmake --build --preset asan
ctest --preset asan ${CTSURG_TEST_ARGS:-}

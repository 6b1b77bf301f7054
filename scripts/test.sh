#!/usr/bin/env bash
# The whole test suite in one command: install dependencies, build, run every test through CTest.
# Real-data tests read ../shared/data and are skipped when it is absent; GPU tests skip without a GPU.
# CTSURG_TEST_ARGS passes extra arguments to ctest (e.g. "-L unit").
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh --tests  # the tools and the test programs; the benchmarks build with scripts/build.sh or bench/run.sh
ctest --preset release ${CTSURG_TEST_ARGS:-}

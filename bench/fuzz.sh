#!/usr/bin/env bash
# bench/fuzz.sh [SECONDS]: the long fuzz run (tests/fuzz/README.md): every target for SECONDS (default
# 600), keeping and growing the corpus in build-fuzz/corpus/ between runs. CI runs 10 s a target.
set -euo pipefail
cd "$(dirname "$0")/.."
exec tests/fuzz/run.sh "${1:-600}"

#!/usr/bin/env bash
# The main job in one command: install dependencies, build, and run the CT-to-scenario pipeline on
# the bundled heart sample (data_samples/heart). Results go to build/demo/heart/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
make --no-print-directory -f scripts/Makefile demo

#!/usr/bin/env bash
# The main job in one command: install dependencies, build, and run the pipeline on the bundled heart
# (data_samples/patients/heart): CT -> HU volume -> grid -> surface -> normal map -> the heart scenarios'
# trajectories -> pictures. Results go to build/demo/heart/; the last lines say what is where.
# CTSURG_JOBS sets make's -j (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh --tools
make --no-print-directory -f scripts/Makefile -j"${CTSURG_JOBS:-2}" demo
echo
cat build/demo/heart/results.txt

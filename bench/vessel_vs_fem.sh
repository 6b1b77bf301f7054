#!/usr/bin/env bash
# The vessel model against full FEM of the same vessel (bench/vessel_vs_fem.cpp; docs/vessel.md,
# "Against full FEM of the same vessel"): builds the program and ctsurg-centerline, makes the aorta's
# centerline from the shared upper-abdomen labels (label 52), runs both cases and both loads.
#
#   bench/vessel_vs_fem.sh [BUILD_DIR] [OUT_DIR] [extra vessel_vs_fem arguments, e.g. --levels 2]
#
# Outputs in OUT_DIR: vessel_vs_fem.md, vessel_vs_fem.csv, aorta_centerline.h5, the cases' inputs.
# About 10 minutes on 2 cores (the quadratic reference takes most of it).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build-dev}"
out="${2:-$here/bench/out/vessel_vs_fem}"
shift $(( $# > 2 ? 2 : $# ))
labels="${CTSURG_DATA:-$here/../shared/data}/abdomen/upper_abdomen_labels.nii.gz"
cmake --build "$build" --target vessel_vs_fem ctsurg-centerline
mkdir -p "$out"
"$build/bin/ctsurg-centerline" "$labels" --label 52 -o "$out/aorta_centerline.h5"
"$build/bin/vessel_vs_fem" --out "$out" --centerline "$out/aorta_centerline.h5" "$@"
echo "wrote $out/vessel_vs_fem.md"

#!/usr/bin/env bash
# Time against error (issue 9), one command: makes the kidney and heart inputs at every resolution
# level (ctsurg-import, -grid, -surface, -tetmesh; cached in OUT/inputs), runs bench time_vs_error on
# the cantilever, kidney and heart scenarios, and copies the Pareto plots to docs/img/.
#   bench/time_vs_error.sh [BUILD_DIR [OUT]]      (default build, build/time_vs_error)
#   QUICK=1 bench/time_vs_error.sh ...            three levels per scenario instead of five
#   SCENARIOS=cantilever,kidney bench/time_vs_error.sh ...
# Writes OUT/runs.csv, OUT/curves.csv, OUT/pareto_*.png, OUT/budgets.md (the table for docs/accuracy.md
# and docs/benchmarks.md). Needs ../shared/data/abdomen for the kidney.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BUILD=${1:-build}
OUT=${2:-$BUILD/time_vs_error}
BIN=$BUILD/bin
DATA=$(cd "$ROOT/.." && pwd)/shared/data
SCENARIOS=${SCENARIOS:-cantilever,kidney,heart}
cmake --build "$BUILD" -j2 --target time_vs_error ctsurg-import ctsurg-grid ctsurg-surface ctsurg-tetmesh >/dev/null
IN=$OUT/inputs
mkdir -p "$IN/kidney" "$IN/heart"
level() {  # level ORGAN CT MASK VOXEL_MM [grid options...]
  local organ=$1 ct=$2 mask=$3 v=$4 d=$IN/$1/v$4
  shift 4
  [[ -f $d/tetmesh.h5 ]] && return 0
  mkdir -p "$d"
  "$BIN/ctsurg-grid" -q "$ct" "$mask" "$d/grid.h5" --voxel-mm "$v" --no-preview "$@"
  "$BIN/ctsurg-surface" -q "$d/grid.h5" "$d/surface.h5"
  "$BIN/ctsurg-tetmesh" -q "$d/grid.h5" "$d/tetmesh.h5" --cell-size "$v"
}
if [[ $SCENARIOS == *kidney* ]]; then
  [[ -f $IN/kidney/ct.h5 ]] || "$BIN/ctsurg-import" -q "$DATA/abdomen/upper_abdomen_ct.nii.gz" "$IN/kidney/ct.h5"
  for v in 6 4.5 3 2.25 1.8; do
    level kidney "$IN/kidney/ct.h5" "$DATA/abdomen/upper_abdomen_labels.nii.gz" $v --labels 2 --keep-largest --fill-holes
  done
fi
if [[ $SCENARIOS == *heart* ]]; then
  [[ -f $IN/heart/ct.h5 ]] || "$BIN/ctsurg-import" -q data_samples/heart/heart_ct.nii.gz "$IN/heart/ct.h5"
  for v in 7.2 4.8 3.6; do level heart "$IN/heart/ct.h5" data_samples/heart/heart_mask.nii.gz $v; done
fi
"$BIN/time_vs_error" --inputs "$IN" --out "$OUT" --scenarios "$SCENARIOS" ${QUICK:+--quick}
mkdir -p docs/img
for f in "$OUT"/pareto_*.png; do cp "$f" docs/img/accuracy_$(basename "$f"); done
cat "$OUT/budgets.md"

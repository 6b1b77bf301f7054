#!/usr/bin/env bash
# Time against error (issues 9 and 16), one command: makes the kidney and heart inputs at every resolution
# level (ctsurg-import, -grid, -surface, -tetmesh; cached in OUT/inputs), runs bench time_vs_error on
# the cantilever, kidney and heart scenarios, and copies the Pareto plots to docs/img/.
#   bench/time_vs_error.sh [BUILD_DIR [OUT]]      (default build, build/time_vs_error)
#   QUICK=1 bench/time_vs_error.sh ...            three levels per scenario instead of five
#   SCENARIOS=cantilever,kidney bench/time_vs_error.sh ...
#   LOCAL_ONLY=1 bench/time_vs_error.sh ...       only the local-region rows (linear, full Neo-Hookean, local R): local_region.md
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
  for v in 7.2 4.8 3.6 2.4; do level heart "$IN/heart/ct.h5" data_samples/heart/heart_mask.nii.gz $v; done
fi
"$BIN/time_vs_error" --inputs "$IN" --out "$OUT" --scenarios "$SCENARIOS" ${QUICK:+--quick} ${LOCAL_ONLY:+--local-only}
# Peak resident memory of the direct solver on the heart's finest levels: ctsurg-sim (the whole tool:
# files, model, surface, factor) on one static frame of the grab, GNU time's maximum RSS.
if [[ $SCENARIOS == *heart* && -z ${QUICK:-} ]]; then
  cmake --build "$BUILD" -j2 --target ctsurg-sim >/dev/null
  {
    echo
    echo "Peak resident memory of ctsurg-sim, one static frame of the heart grab (the direct solver's factor included):"
    echo
    echo "| model | level | nodes | peak memory (MiB) | wall (s) |"
    echo "|---|---:|---:|---:|---:|"
  } >>"$OUT/budgets.md"
  for run in "neo_hookean linear 2.4" "neo_hookean quadratic 3.6" "neo_hookean quadratic 4.8"; do
    read -r law elements v <<<"$run"
    d=$IN/heart/v$v
    cat >"$OUT/memory.yaml" <<EOF
ctsurg_scenario: 1
model: {kind: fem, tetmesh: $d/tetmesh.h5, surface: $d/surface.h5, solver: static, elements: $elements}
material: {law: $law, preset: myocardium}
fixed:
  - box_fraction: {min: [0, 0, 0.85], max: [1, 1, 1]}
tools:
  - grab: {radius_mm: 8, snap_to_tissue: true, path: [{t: 0, at_fraction: [0.75, 0.0, 0.2]}, {t: 0.25, offset_mm: [5, -12.5, -5]}]}
time: {duration_s: 0.25}
output: {trajectory: $OUT/memory.h5, frame_interval_s: 0.25}
solver: {tolerance_mm: 0.01}
EOF
    /usr/bin/time -f "%M %e" -o "$OUT/memory.time" "$BIN/ctsurg-sim" -v "$OUT/memory.yaml" 2>"$OUT/memory.log" >/dev/null
    read -r kib secs <"$OUT/memory.time"
    nodes=$(grep -oE '[0-9]+ nodes \(' "$OUT/memory.log" | head -1 | awk '{print $1}')
    echo "| $law $elements tets | h $v mm | ${nodes:-?} | $((kib / 1024)) | $secs |" >>"$OUT/budgets.md"
  done
  rm -f "$OUT/memory.yaml" "$OUT/memory.h5" "$OUT/memory.xdmf" "$OUT/memory.time"
fi
# Only a full run's plots replace the documented ones (a QUICK or LOCAL_ONLY run has fewer levels or
# configurations: its plots stay in OUT).
if [[ -z ${QUICK:-} && -z ${LOCAL_ONLY:-} ]]; then
  mkdir -p docs/img
  for f in "$OUT"/pareto_*.png; do cp "$f" docs/img/accuracy_$(basename "$f"); done
fi
cat "$OUT/budgets.md"

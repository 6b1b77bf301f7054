#!/usr/bin/env bash
# The Snakefile (scripts/Snakefile) on a tiny synthetic patient with --cores 2; skipped (exit 77)
# when snakemake is not installed. Usage: snakefile_test.sh ROOT BIN WORK
ROOT=$1 BIN=$2 WORK=$3
source "$(dirname "$0")/pipeline_test_lib.sh"
command -v snakemake > /dev/null || { echo "snakemake not installed: skipped"; exit 77; }
rm -rf "$WORK" && mkdir -p "$WORK/patients"
phantom_ct "$WORK/patients/sphere"
scenario "$WORK/patients/sphere/scenarios/pull.yaml" spring_grid surface_textured.h5 viewer
# Every kind of picture the Makefile makes (scripts/render_plan.py): one frame, several frames, the viewer.
echo '  - {name: pull_frames, layout: single, frames: all, size: 48}' >> "$WORK/patients/sphere/scenarios/pull.yaml"
scenario "$WORK/patients/sphere/scenarios/still.yaml" spring_grid surface.h5 no
cd "$WORK"
sm() { snakemake -s "$ROOT/scripts/Snakefile" --cores 2 --config patients_dir="$WORK/patients" out="$WORK/out" \
         bin="$BIN" python="$PY" "$@"; }
sm --quiet > snake.log 2>&1 || { cat snake.log; fail "snakemake run failed"; }
for f in pull.h5 pull_picture.png pull_3d.html pull_3d.glb pull_frames.frames pull_frames/pull_frames_0000.png still.h5 \
         surface_textured.h5 results.txt; do
  [[ -f "$WORK/out/sphere/$f" ]] || fail "missing $f"
done
[[ ! -e "$WORK/out/sphere/tetmesh.h5" ]] || fail "tet mesh built though no scenario needs it"
sm -n > dry.log 2>&1
grep -q "Nothing to be done" dry.log || { cat dry.log; fail "rerun is not a no-op"; }
echo "PASS"

#!/usr/bin/env bash
# The FEM paper's experiment (Huang et al., Table 1) redone on the right kidney of the shared abdomen
# sample: the same point force on the same mesh with linear (small-strain) elasticity, St. Venant-
# Kirchhoff (Green-Lagrange strain, the paper's nonlinear model) and Neo-Hookean, static equilibrium;
# volume and surface area of the embedded surface before and after, and the largest displacement.
# Also the calibrated spring grid under the same force (damped dynamics, 1.5 s), for comparison.
#
#   bench/kidney_experiment.sh [FORCES_N...]     (default: 0.1 0.2 0.4) -> markdown table on stdout
# Needs ../shared/data/abdomen; build/bin from scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BIN=$ROOT/build/bin
DATA=$(cd "$ROOT/.." && pwd)/shared/data/abdomen
[[ -e $DATA/upper_abdomen_ct.nii.gz ]] || { echo "kidney_experiment.sh: $DATA is missing" >&2; exit 2; }
[[ $# -gt 0 ]] && FORCES=("$@") || FORCES=(0.1 0.2 0.4)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
"$BIN/ctsurg-import" -q "$DATA/upper_abdomen_ct.nii.gz" ct.h5
"$BIN/ctsurg-grid" -q ct.h5 "$DATA/upper_abdomen_labels.nii.gz" grid.h5 --labels 2 --label-names 2=kidney_right \
  --keep-largest --fill-holes --voxel-mm 3 --no-preview
"$BIN/ctsurg-surface" -q grid.h5 surface.h5
"$BIN/ctsurg-tetmesh" -q grid.h5 tetmesh.h5
PY=/usr/bin/python3

# scenario NAME MODEL_YAML FORCE_N DURATION FRAME [LAW]: the lower 15 % of the kidney (inferior pole) held, a
# lateral force on the 6 mm around the superior-medial surface point.
scenario() {
  cat >"$1.yaml" <<YAML
ctsurg_scenario: 1
name: kidney $1
model: $2
material: {preset: kidney, damping_per_s: 60${6:+, law: $6}}
fixed:
  - box_fraction: {min: [0, 0, 0], max: [1, 1, 0.15]}
tools:
  - force:
      radius_mm: 6
      force_n: [$3, 0, 0]
      snap_to_tissue: true
      path:
        - {t: 0, at_fraction: [0, 0.5, 0.85]}
time: {duration_s: $4}
output: {trajectory: $1.h5, frame_interval_s: $5}
YAML
}

echo "| force (N) | model | volume before (mm³) | volume after | change | area before (mm²) | area after | change | max displacement (mm) | time (s) | Newton iterations | CG iterations |"
echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for f in "${FORCES[@]}"; do
  for law in linear stvk neo_hookean grid; do
    if [[ $law == grid ]]; then
      scenario "$law-$f" "{kind: spring_grid, grid: grid.h5, surface: surface.h5}" "$f" 1.5 0.5
    else
      scenario "$law-$f" "{kind: fem, tetmesh: tetmesh.h5, surface: surface.h5, solver: static}" "$f" 1 1 "$law"
    fi
    start=$(date +%s.%N)
    if "$BIN/ctsurg-sim" -q "$law-$f.yaml" 2>"$law-$f.err"; then
      secs=$(awk "BEGIN{printf \"%.2f\", $(date +%s.%N) - $start}")
      $PY - "$law-$f.h5" "$f" "$law" "$secs" <<'PYEOF'
import sys, h5py
path, force, law, secs = sys.argv[1:]
m = h5py.File(path, "r")["trajectory/metrics"]
v, a, u = m["enclosed_volume"][:], m["surface_area"][:], m["max_displacement"][:]
names = {"linear": "FEM linear", "stvk": "FEM StVK", "neo_hookean": "FEM Neo-Hookean", "grid": "spring grid (calibrated)"}
it = m["newton_iterations"][-1] if "newton_iterations" in m else None
cg = m["cg_iterations"][-1] if "cg_iterations" in m else None
print(f"| {force} | {names[law]} | {v[0]:.0f} | {v[-1]:.0f} | {100*(v[-1]/v[0]-1):+.2f} % | {a[0]:.0f} | {a[-1]:.0f} | "
      f"{100*(a[-1]/a[0]-1):+.2f} % | {u[-1]:.2f} | {secs} | {'' if it is None else int(it)} | {'' if cg is None else int(cg)} |")
PYEOF
    else
      echo "| $f | $law | failed: $(tail -1 "$law-$f.err" | cut -c1-160) | | | | | | | | | |"
    fi
  done
done

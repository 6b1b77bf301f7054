#!/usr/bin/env bash
# The live heart's own discretisation error, against a reference extrapolated from nested refinements
# of its mesh (issue 32, item 2: a converged reference for the live drag).
#
#   bench/nested_convergence.sh [BUILD_DIR [OUT]]      (about 55 min on 2 cores, 17 GiB at most)
#
# The demo's heart mesh (6 mm tets, 3,529 nodes: BUILD_DIR/demo/heart/tetmesh.h5, made by `make -f
# scripts/Makefile demo` or bench/run.sh live) is refined uniformly once and twice (ctsurg-tetmesh
# --refine: every tet into eight at its edges' midpoints; 24,471 and 180,069 nodes), so the three meshes
# share one domain, one boundary and one fixed plane: only the discretisation differs between them. On
# each, the live drag (bench/live_drag_error.sh: an 8 mm grab at the apex dragged 25 mm along (10, -25,
# -10) in 3 s, the base fixed, Neo-Hookean, the 16,163-vertex textured surface embedded), its grab
# centre put where the live model's snap puts it (the 6 mm mesh's node nearest the apex point, the same
# absolute position on every mesh) and solved at t = 1.03, 2.07 and 3.10 s (frames 31, 62 and 93 of the
# live run's 1/30 s): linear tets (P1) on the three meshes with the grab holding the material (grip:
# volume, which converges) and with it holding the nodes in its sphere (grip: nodes, what the live grab
# does); quadratic tets (P2) on the first two meshes with the volume grip, on the first with the node
# grip; quasi-Newton to 1e-3 mm. The live model itself (P1 on the 6 mm mesh,
# node grip, heart_live.yaml's solver, a frame every 1/30 s) is run too. bench/nested_convergence.py
# then gives the observed order of each sequence, the Richardson-extrapolated surface (the reference) and
# its estimated error, and every case's distance from it. Results: OUT/nested_convergence.md (copied
# into docs/accuracy.md "The live mesh's own error" by hand, with the machine and date).
# What sets the P1 error on these meshes (locking or cells through the walls): bench/linear_tet_error.py
# OUT/mesh0.h5 OUT/mesh1.h5 OUT/mesh2.h5 (docs/accuracy.md "What sets the linear tets' error").
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
OUT=${2:-$BUILD/nested_convergence}
BIN=$BUILD/bin
HEART=$BUILD/demo/heart
for f in tetmesh.h5 surface_textured.h5; do
  [[ -f $HEART/$f ]] || { echo "nested_convergence.sh: $HEART/$f is missing (make -f scripts/Makefile demo, or bench/run.sh live)" >&2; exit 2; }
done
cmake --build "$BUILD" -j2 --target ctsurg-tetmesh ctsurg-sim >/dev/null
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
HEART=$(realpath "$HEART")
source bench/nested_meshes.sh
nested_meshes "$BIN" "$HEART/tetmesh.h5" "$OUT"
# The grab's centre: the 6 mm mesh's node nearest heart_fem_grab.yaml's apex point (at_fraction
# (0.75, 0, 0.2) of the nodes' bounds, identical on the nested meshes), as its snap_to_tissue finds it.
read -r cx cy cz < <(snapped_node "$OUT/mesh0.h5" 0.75 0 0.2)
LIVE_SOLVER=$(/usr/bin/python3 -c 'import yaml,json; print(json.dumps(yaml.safe_load(open("data_samples/scenarios/heart_live.yaml"))["solver"]))')
LIVE_INTERVAL=$(/usr/bin/python3 -c 'import yaml; print(repr(yaml.safe_load(open("data_samples/scenarios/heart_live.yaml"))["output"]["frame_interval_s"]))')
# Every 31st of the live run's frames.
REF_INTERVAL=$(/usr/bin/python3 -c "print(repr(31 * $LIVE_INTERVAL))")
run() {  # run NAME MESH ELEMENTS GRIP SOLVER INTERVAL
  local name=$1 mesh=$2 elements=$3 grip=$4 solver=$5 interval=$6
  [[ -f $OUT/$name.h5 ]] && return 0
  cat >"$OUT/$name.yaml" <<YAML
ctsurg_scenario: 1
name: nested convergence $name
model: {kind: fem, tetmesh: $OUT/$mesh.h5, surface: $HEART/surface_textured.h5, solver: static, elements: $elements}
material: {law: neo_hookean, preset: myocardium}
gravity_mm_per_s2: [0, 0, 0]
fixed:
  - box_fraction: {min: [0, 0, 0.85], max: [1, 1, 1]}
tools:
  - grab: {radius_mm: 8, grip: $grip, start_s: 0.1, end_s: 3.2, path: [{t: 0.1, position_mm: [$cx, $cy, $cz]}, {t: 3.1, offset_mm: [8.704, -21.76, -8.704]}]}
time: {duration_s: 3.1}
output: {trajectory: $OUT/$name.h5, frame_interval_s: $interval}
solver: $solver
YAML
  echo "nested_convergence.sh: $name" >&2
  /usr/bin/time -f "%M %e" -o "$OUT/$name.time" "$BIN/ctsurg-sim" -v "$OUT/$name.yaml" 2>"$OUT/$name.log" >/dev/null
}
REF_SOLVER="{nonlinear: quasi_newton, tolerance_mm: 0.001}"
run live mesh0 linear nodes "$LIVE_SOLVER" "$LIVE_INTERVAL"
for grip in volume nodes; do
  for k in 0 1 2; do run "p1_m${k}_$grip" "mesh$k" linear "$grip" "$REF_SOLVER" "$REF_INTERVAL"; done
done
# P2 on 180,069 nodes takes 25 min and 17 GiB: with the volume grip only.
run p2_m0_volume mesh0 quadratic volume "$REF_SOLVER" "$REF_INTERVAL"
run p2_m1_volume mesh1 quadratic volume "$REF_SOLVER" "$REF_INTERVAL"
run p2_m0_nodes mesh0 quadratic nodes "$REF_SOLVER" "$REF_INTERVAL"
/usr/bin/python3 bench/nested_convergence.py "$OUT" | tee "$OUT/nested_convergence.md"

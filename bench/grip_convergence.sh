#!/usr/bin/env bash
# Does the heart's accuracy drag converge as its tets are refined, with the grab holding nodes and with it
# holding the material (grip: volume, sim/fem/fem_grip.h)? Issue 32, items 1 and 2.
#
#   bench/grip_convergence.sh [BUILD_DIR [OUT]]      (about 25 min on 2 cores, 8.3 GiB at most; LEVELS="7.2 4.8" for fewer)
#
# The geometry is held fixed across levels, so that only the discretisation changes: one grid and one
# surface (at 2.4 mm voxels, embedded in each level's tets), every level's tets meshing the same
# full-resolution mask with their boundary within FACET_MM (0.5) of it, the grab's centre and the fixed
# plane in absolute coordinates (from the finest level's tet bounds: the apex point heart_grab.yaml
# names by fraction, and the top 15 %). At each level (h 7.2, 4.8, 3.6 mm) Neo-Hookean static FEM on
# quadratic tets, solved to 1e-3 mm: the 8 mm sphere at the apex pulled (5, -12.5, -5) mm in 4 frames,
# once with grip: nodes and once with grip: volume; and at the middle level with radii 7.75 and 8.25 mm.
# The surface's displacement at the end is compared between levels and between radii (RMS, 95th
# percentile and max over its vertices), the grab's pull (the trajectory's sphere_loads) reported, and a
# Richardson estimate of the finest level's own error given from the three levels
# (bench/grip_convergence.py). Results: OUT/convergence.md (copied into docs/accuracy.md by hand, with
# the machine and date).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
OUT=${2:-$BUILD/grip_convergence}
BIN=$BUILD/bin
LEVELS=${LEVELS:-"7.2 4.8 3.6"}
IN=${IN:-$BUILD/time_vs_error/inputs}
cmake --build "$BUILD" -j2 --target ctsurg-import ctsurg-grid ctsurg-surface ctsurg-tetmesh ctsurg-sim >/dev/null
mkdir -p "$OUT" "$IN/heart"
OUT=$(realpath "$OUT")
IN=$(realpath "$IN")
[[ -f $IN/heart/ct.h5 ]] || "$BIN/ctsurg-import" -q data_samples/heart/heart_ct.nii.gz "$IN/heart/ct.h5"
# One grid (its full-resolution mask is what every level meshes) and one surface; each level's tets
# approximate the mask's boundary to FACET_MM whatever their size, so that the domain is the same to
# that distance at every level (the default, half the grid's voxel, would let the boundary move by up to
# 1.8-3.6 mm between time_vs_error.sh's levels and measure that instead of the discretisation).
FACET_MM=${FACET_MM:-0.5}
G=$IN/heart_fixed_geometry
mkdir -p "$G"
[[ -f $G/grid.h5 ]] || "$BIN/ctsurg-grid" -q "$IN/heart/ct.h5" data_samples/heart/heart_mask.nii.gz "$G/grid.h5" --voxel-mm 2.4 --no-preview
[[ -f $G/surface.h5 ]] || "$BIN/ctsurg-surface" -q "$G/grid.h5" "$G/surface.h5"
for v in $LEVELS; do
  [[ -f $G/tetmesh_$v.h5 ]] || "$BIN/ctsurg-tetmesh" -q "$G/grid.h5" "$G/tetmesh_$v.h5" --cell-size "$v" --facet-distance "$FACET_MM"
done
finest=${LEVELS##* }
# The grab's centre and the fixed plane from the finest level's tet bounds (LPS mm).
read -r cx cy cz zfix < <(/usr/bin/python3 - "$G/tetmesh_$finest.h5" <<'EOF'
import sys, h5py, numpy as np
n = h5py.File(sys.argv[1], "r")["/tetmesh/nodes"][:]
lo, hi = n.min(0), n.max(0)
c = lo + np.array([0.75, 0.0, 0.2]) * (hi - lo)   # heart_grab.yaml's apex: at_fraction [0.75, 0, 0.2]
print(f"{c[0]:.4f} {c[1]:.4f} {c[2]:.4f} {lo[2] + 0.85 * (hi[2] - lo[2]):.4f}")
EOF
)
run() {  # run NAME LEVEL GRIP RADIUS
  local name=$1 v=$2 grip=$3 r=$4
  [[ -f $OUT/$name.h5 ]] && return 0
  cat >"$OUT/$name.yaml" <<EOF
ctsurg_scenario: 1
name: heart grab convergence, h $v, grip $grip, radius $r
model: {kind: fem, tetmesh: $G/tetmesh_$v.h5, surface: $G/surface.h5, solver: static, elements: quadratic}
material: {law: neo_hookean, preset: myocardium}
gravity_mm_per_s2: [0, 0, 0]
fixed:
  - box: {min: [-1000, -1000, $zfix], max: [1000, 1000, 1000]}
tools:
  - grab: {radius_mm: $r, grip: $grip, snap_to_tissue: false, path: [{t: 0, position_mm: [$cx, $cy, $cz]}, {t: 0.25, offset_mm: [5, -12.5, -5]}]}
time: {duration_s: 0.25}
output: {trajectory: $OUT/$name.h5, frame_interval_s: 0.0625}
solver: {nonlinear: quasi_newton, tolerance_mm: 0.001}
EOF
  /usr/bin/time -f "%M %e" -o "$OUT/$name.time" "$BIN/ctsurg-sim" -v "$OUT/$name.yaml" 2>"$OUT/$name.log" >/dev/null
}
for v in $LEVELS; do
  for grip in nodes volume; do run "v${v}_$grip" "$v" "$grip" 8; done
done
# How much the answer moves when the sphere's radius moves by a quarter millimetre, at the middle level.
read -r -a levels <<<"$LEVELS"
mid=${levels[$(( ${#levels[@]} / 2 ))]}
for grip in nodes volume; do
  for r in 7.75 8.25; do run "v${mid}_${grip}_r$r" "$mid" "$grip" "$r"; done
done
/usr/bin/python3 bench/grip_convergence.py "$OUT" "$mid" $LEVELS >"$OUT/convergence.md"
cat "$OUT/convergence.md"

#!/usr/bin/env bash
# Does the kidney's point force converge as its mesh is refined? The force shared equally by the nodes in
# its sphere (the bundled kidney scenarios) against the same force spread over the material by volume
# (force with grip: volume, docs/fem.md "Volume grips"), on nested meshes of one domain.
#
#   bench/force_convergence.sh [BUILD_DIR [OUT]]      (about 18 min on 2 cores, 11 GiB at most)
#
# The kidney's tet mesh from the batch pipeline (BUILD_DIR/pipeline/kidney/tetmesh.h5 and
# surface_textured.h5: `make -f scripts/Makefile batch`; needs ../shared/data/abdomen) is refined
# uniformly once and twice (ctsurg-tetmesh --refine), so the meshes share one domain, one boundary and
# one fixed region. On each, data_samples/scenarios/kidney_fem_neo_hookean.yaml's load (the inferior
# 15 % held, 0.2 N along +x over a 6 mm sphere) with its centre put at the coarse mesh's node nearest the
# scenario's superior-medial point (where its snap_to_tissue puts it; the same absolute position on every
# mesh): Neo-Hookean static, linear tets on the three meshes and quadratic on the first two, the force
# shared by the nodes and by volume. The embedded surface is the same file on every mesh, so its
# vertices compare one to one: for each sequence the RMS change of the surface between levels and the
# observed order. Results: OUT/force_convergence.md (copied into docs/fem.md by hand, with machine and date).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
OUT=${2:-$BUILD/force_convergence}
BIN=$BUILD/bin
KIDNEY=$BUILD/pipeline/kidney
for f in tetmesh.h5 surface_textured.h5; do
  [[ -f $KIDNEY/$f ]] || { echo "force_convergence.sh: $KIDNEY/$f is missing (make -f scripts/Makefile batch)" >&2; exit 2; }
done
cmake --build "$BUILD" -j2 --target ctsurg-tetmesh ctsurg-sim >/dev/null
mkdir -p "$OUT"
OUT=$(realpath "$OUT")
KIDNEY=$(realpath "$KIDNEY")
source bench/nested_meshes.sh
nested_meshes "$BIN" "$KIDNEY/tetmesh.h5" "$OUT"
# The scenario's point (at_fraction (0, 0.5, 0.85) of the nodes' bounds) snapped to the coarse mesh's
# nearest node, as snap_to_tissue does.
read -r cx cy cz < <(snapped_node "$OUT/mesh0.h5" 0 0.5 0.85)
run() {  # run NAME MESH ELEMENTS GRIP
  local name=$1 mesh=$2 elements=$3 grip=$4
  [[ -f $OUT/$name.h5 ]] && return 0
  cat >"$OUT/$name.yaml" <<YAML
ctsurg_scenario: 1
name: force convergence $name
model: {kind: fem, tetmesh: $OUT/$mesh.h5, surface: $KIDNEY/surface_textured.h5, solver: static, elements: $elements}
material: {law: neo_hookean, preset: kidney}
gravity_mm_per_s2: [0, 0, 0]
fixed:
  - box_fraction: {min: [0, 0, 0], max: [1, 1, 0.15]}
tools:
  - force: {radius_mm: 6, force_n: [0.2, 0, 0], grip: $grip, path: [{t: 0, position_mm: [$cx, $cy, $cz]}]}
time: {duration_s: 0.25}
output: {trajectory: $OUT/$name.h5, frame_interval_s: 0.25}
YAML
  echo "force_convergence.sh: $name" >&2
  /usr/bin/time -f "%M %e" -o "$OUT/$name.time" "$BIN/ctsurg-sim" -v "$OUT/$name.yaml" 2>"$OUT/$name.log" >/dev/null
}
for grip in nodes volume; do
  for k in 0 1 2; do run "p1_m${k}_$grip" "mesh$k" linear "$grip"; done
  for k in 0 1; do run "p2_m${k}_$grip" "mesh$k" quadratic "$grip"; done
done
/usr/bin/python3 - "$OUT" <<'PY' | tee "$OUT/force_convergence.md"
import pathlib, sys
import h5py
import numpy as np
out = pathlib.Path(sys.argv[1])
def last(name):
    with h5py.File(out / f"{name}.h5", "r") as f:
        t = f["/trajectory"]
        return t["surface/vertices"][-1].astype(np.float64), int(t["metrics/nodes"][-1])
def rms(d):
    return float(np.sqrt((d ** 2).mean()))
print("| force shared | elements | nodes | largest surface displacement (mm) | RMS change to the next level (mm) | observed order |")
print("|---|---|---|---|---|---:|")
with h5py.File(out / "p1_m0_nodes.h5", "r") as f:
    rest = f["/trajectory/surface/rest_vertices"][:].astype(np.float64)
for grip, label in (("nodes", "by the nodes in the sphere"), ("volume", "by volume (grip: volume)")):
    for order, levels in (("p1", 3), ("p2", 2)):
        runs = [last(f"{order}_m{k}_{grip}") for k in range(levels)]
        changes = [rms(np.linalg.norm(runs[k + 1][0] - runs[k][0], axis=1)) for k in range(levels - 1)]
        p = f"{np.log2(changes[0] / changes[1]):.2f}" if len(changes) == 2 and changes[1] > 0 else "-"
        print(f"| {label} | {'linear' if order == 'p1' else 'quadratic'} | {', '.join(f'{n:,}' for _, n in runs)} | "
              f"{', '.join(f'{np.linalg.norm(v - rest, axis=1).max():.3f}' for v, _ in runs)} | "
              f"{', '.join(f'{c:.4f}' for c in changes)} | {p} |")
PY

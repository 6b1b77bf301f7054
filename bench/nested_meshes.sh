# Sourced by the nested-refinement studies (bench/nested_convergence.sh, bench/force_convergence.sh):
#
#   nested_meshes BIN MESH OUT    copies MESH to OUT/mesh0.h5 and refines it uniformly once and twice
#                                 (BIN/ctsurg-tetmesh --refine) into OUT/mesh1.h5, OUT/mesh2.h5 (kept
#                                 when present), so the three share one domain and boundary
#   snapped_node MESH FX FY FZ    prints the node of MESH nearest the point at fraction (FX, FY, FZ) of
#                                 its nodes' bounds (what a scenario's at_fraction + snap_to_tissue picks
#                                 on that mesh), as "x y z" mm, to put a tool at one absolute position on
#                                 every level
nested_meshes() {
  local bin=$1 mesh=$2 out=$3 k
  cp -f "$mesh" "$out/mesh0.h5"
  for k in 1 2; do
    [[ -f $out/mesh$k.h5 ]] || "$bin/ctsurg-tetmesh" -q --import "$out/mesh0.h5" --refine "$k" "$out/mesh$k.h5"
  done
}

snapped_node() {
  /usr/bin/python3 - "$@" <<'PY'
import sys, h5py, numpy as np
n = h5py.File(sys.argv[1], "r")["/tetmesh/nodes"][:]
lo, hi = n.min(0), n.max(0)
p = lo + np.array([float(x) for x in sys.argv[2:5]]) * (hi - lo)
c = n[np.argmin(((n - p) ** 2).sum(1))]
print(f"{c[0]!r} {c[1]!r} {c[2]!r}")
PY
}

#!/usr/bin/env bash
# Reruns every benchmark with one command and rewrites docs/benchmarks.md (machine and date included).
#   bench/run.sh                 build (Release) if needed, then run every section
#   bench/run.sh render fem      only these sections (preprocess tetmesh surface sim render fem collision instruments vessel
#                                kidney accuracy live);
#                                the others in docs/benchmarks.md stay as they are
#   BUILD=build-dev bench/run.sh fem        an existing build folder (brought up to date) instead of the release preset
#   TVE_OUT=DIR bench/run.sh accuracy       the tables of a finished bench/time_vs_error.sh run in DIR, not a new run
# Real volumes come from ../shared/data; a volume that is absent is left out of the table.
# Wall times are the best of REPEAT runs (default 3); peak memory is the maximum resident set size
# reported by GNU time for the whole process.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
REPEAT=${REPEAT:-3}
SECTIONS=("$@")
want() {  # want SECTION: true when SECTION was asked for (or nothing was: every section)
  [[ ${#SECTIONS[@]} -eq 0 ]] && return 0
  local x
  for x in "${SECTIONS[@]}"; do [[ $x == "$1" ]] && return 0; done
  return 1
}
if [[ -n ${BUILD:-} ]]; then
  cmake --build "$BUILD" >/dev/null
  BIN=$(cd "$BUILD" && pwd)/bin
else
  BUILD=build
  scripts/build.sh >/dev/null
  BIN=$ROOT/build/bin
fi
DATA=$(cd "$ROOT/.." && pwd)/shared/data
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
TIME=/usr/bin/time
[[ -x $TIME ]] || { echo "bench/run.sh: GNU time (/usr/bin/time) is needed: apt-get install time" >&2; exit 2; }

# best_of CMD...: runs CMD REPEAT times; prints "seconds peak_kib" of the fastest run.
best_of() {
  local best="" mem=0
  for _ in $(seq "$REPEAT"); do
    $TIME -f "%e %M" -o "$WORK/t" "$@" >/dev/null 2>"$WORK/err" || { cat "$WORK/err" >&2; return 1; }
    read -r s m <"$WORK/t"
    if [[ -z $best ]] || awk "BEGIN{exit !($s < $best)}"; then best=$s; fi
    ((m > mem)) && mem=$m
  done
  echo "$best $mem"
}

# Numbers the tools log (stderr of the last run): "A x B x C voxels" and "N particles".
logged_voxels() { grep -oE '[0-9]+ x [0-9]+ x [0-9]+ voxels' "$WORK/err" | head -1 | awk '{print $1*$3*$5}'; }
logged_particles() { grep -oE '[0-9]+ particles' "$WORK/err" | head -1 | awk '{print $1}'; }

out=$WORK/preprocess.md
{
  echo "## Preprocess: import and grid (\`bench/run.sh\`)"
  echo
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}') ($(nproc) cores), $(free -g | awk '/Mem:/{print $2}') GiB;"
  echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build."
  echo "Whole-tool wall time (best of $REPEAT, including HDF5 compression, hashing and the XDMF sidecar) and peak resident memory."
  echo
  echo "| step | input | voxels | time (s) | voxels/s | peak memory (MiB) |"
  echo "|---|---|---:|---:|---:|---:|"
} >"$out"

declare -A VOXELS  # CT voxel count by imported file
import_case() {  # name input [options...]
  local name=$1 input=$2
  shift 2
  [[ -e $input ]] || return 0
  read -r s m < <(best_of "$BIN/ctsurg-import" "$input" "$WORK/$name.h5" "$@")
  local n
  n=$(logged_voxels)
  VOXELS[$WORK/$name.h5]=$n
  printf '| import | %s | %s | %.2f | %.3g | %d |\n' "$name" "$n" "$s" "$(awk "BEGIN{print $n/($s>0?$s:0.01)}")" $((m / 1024)) >>"$out"
}
grid_case() {  # name ct.h5 [mask] -- options...
  local name=$1
  shift
  local args=()
  while [[ $1 != -- ]]; do args+=("$1"); shift; done
  shift
  [[ -e ${args[0]} ]] || return 0
  read -r s m < <(best_of "$BIN/ctsurg-grid" "${args[@]}" "$WORK/grid_$name.h5" --no-preview "$@")
  local n p
  p=$(logged_particles)
  n=${VOXELS[${args[0]}]}
  printf '| grid (%s particles) | %s | %s | %.2f | %.3g | %d |\n' "$p" "$name" "$n" "$s" "$(awk "BEGIN{print $n/($s>0?$s:0.01)}")" $((m / 1024)) >>"$out"
}

if want preprocess || want tetmesh || want surface; then
import_case heart_nifti "$ROOT/data_samples/heart/heart_ct.nii.gz"
import_case abdomen_nifti "$DATA/abdomen/abdomen_ct.nii.gz"
import_case head_nrrd "$DATA/headsq/quarter.nhdr" --rescale-intercept -1024
import_case philips_dicom "$DATA/dicom_qa/Philips_S21570_S2010"
import_case ge_dicom_tilted_resampled "$DATA/dicom_qa/GE"
import_case ge_dicom_tilted_kept "$DATA/dicom_qa/GE" --uneven-slices keep
import_case abdomen_dicom_jpeg2000 "$DATA/abdomen/dicom_j2k"
import_case upper_abdomen_nifti "$DATA/abdomen/upper_abdomen_ct.nii.gz"

grid_case heart_2.4mm "$WORK/heart_nifti.h5" "$ROOT/data_samples/heart/heart_mask.nii.gz" -- --voxel-mm 2.4
grid_case heart_100cube "$WORK/heart_nifti.h5" "$ROOT/data_samples/heart/heart_mask.nii.gz" -- --max-dim 100
grid_case kidneys_3mm "$WORK/upper_abdomen_nifti.h5" "$DATA/abdomen/upper_abdomen_labels.nii.gz" -- --labels 2,3 --voxel-mm 3
grid_case head_otsu "$WORK/head_nrrd.h5" -- --otsu --voxel-mm 3.2 --keep-largest

{
  echo
  echo "Kernel throughput (Google Benchmark, \`build/bin/bench_occupancy_downsampling\`): exact fractional"
  echo "occupancy of the 1.4 M-voxel heart mask, full-resolution voxels per second."
  echo
  echo "| cells (mm) | threads | time (ms) | voxels/s | particles |"
  echo "|---:|---:|---:|---:|---:|"
  "$BIN/bench_occupancy_downsampling" --benchmark_format=csv 2>/dev/null |
    awk -F, '/BM_DownsampleHeart/{split($1,a,/[:\/]/); n=split($1,p,"/"); c=p[2]; sub(/.*:/,"",c); t=p[3]; sub(/.*:/,"",t);
      printf "| %.1f | %s | %.1f | %.3g | %d |\n", c/10, t, $3, $7, $(NF)}'
} >>"$out"
fi

# splice SECTION FILE: puts FILE between <!-- bench:SECTION:start/end --> in docs/benchmarks.md
# (appending the markers when absent); the other sections stay as they are.
doc=docs/benchmarks.md
[[ -f $doc ]] || printf '# Benchmarks\n\nRerun with `bench/run.sh`.\n' >"$doc"
splice() {
  local section=$1 file=$2
  grep -q "<!-- bench:$section:start -->" "$doc" || printf '\n<!-- bench:%s:start -->\n<!-- bench:%s:end -->\n' "$section" "$section" >>"$doc"
  awk -v f="$file" -v a="<!-- bench:$section:start -->" -v b="<!-- bench:$section:end -->" '
    $0 == a {print; while ((getline l < f) > 0) print l; skip=1; next}
    $0 == b {skip=0}
    !skip' "$doc" >"$WORK/doc" && mv "$WORK/doc" "$doc"
  cat "$file"
}
machine_line() {
  echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}') ($(nproc) cores), $(free -g | awk '/Mem:/{print $2}') GiB;"
}
want preprocess && splice preprocess "$out"

# Tetrahedral meshes: ctsurg-tetmesh (CGAL Mesh_3) on the heart grid against TetGen (when installed)
# meshing the marching-cubes surface of the same grid at a similar tet count. TetGen's mesh is rated
# by bench/tet_quality.py with the measures of mesh/include/ctsurg/mesh/tet_mesh_quality.h.
tet=$WORK/tetmesh.md
heart_grid=$WORK/grid_heart_2.4mm.h5
if want tetmesh && [[ -e $heart_grid ]]; then
  {
    echo "## Tetrahedral meshes: heart (\`bench/run.sh\`)"
    echo
    echo "Machine: $(lscpu | awk -F: '/Model name/{gsub(/^ +/,"",$2); print $2}') ($(nproc) cores), $(free -g | awk '/Mem:/{print $2}') GiB;"
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build;"
    echo "$(command -v tetgen >/dev/null && dpkg-query -W -f='TetGen ${Version} (Debian)' tetgen 2>/dev/null || echo 'TetGen absent')."
    echo "The bundled heart's occupancy grid (2.4 mm cells). ctsurg-tetmesh meshes the full-resolution mask with its"
    echo "defaults (cell and facet size 2.4 mm, facet distance 0.75 mm, radius-edge 2, facet angle 25 deg, sliver"
    echo "perturbation and exudation towards 12 deg), without and with ODT smoothing; TetGen meshes the grid's"
    echo "marching-cubes surface (\`ctsurg-surface grid.h5 heart.ply\`) with \`-pYq1.414a6\` (surface kept, radius-edge"
    echo "1.414, tets up to 6 mm^3: a similar tet count). Wall time best of $REPEAT (TetGen: meshing only), peak"
    echo "resident memory; slivers: tets with a dihedral angle under 10 deg; mask voxel volume 668,844 mm^3."
    echo
    echo "| mesher | nodes | tets | min dihedral (deg) | max dihedral (deg) | slivers | mean / max radius-edge | volume (mm^3) | time (s) | peak memory (MiB) |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
  } >"$tet"
  for opt in none odt; do
    read -r s m < <(best_of "$BIN/ctsurg-tetmesh" "$heart_grid" "$WORK/heart_tet.h5" --optimiser "$opt")
    read -r nodes tets < <(sed -nE 's/.*tetmesh: ([0-9]+) nodes, ([0-9]+) tets.*/\1 \2/p' "$WORK/err")
    read -r dmin dmax sl < <(sed -nE 's/.*dihedral angles ([0-9.]+) \.\. ([0-9.]+) deg; ([0-9]+) slivers.*/\1 \2 \3/p' "$WORK/err")
    read -r remax remean < <(sed -nE 's/.*radius-edge ratio [0-9.]+ \.\. ([0-9.]+), mean ([0-9.]+).*/\1 \2/p' "$WORK/err")
    vol=$(sed -nE 's/.*mesh volume ([0-9.]+) mm\^3.*/\1/p' "$WORK/err")
    printf '| ctsurg-tetmesh (CGAL Mesh_3, optimiser %s) | %s | %s | %s | %s | %s | %s / %s | %.0f | %.2f | %d |\n' \
      "$opt" "$nodes" "$tets" "$dmin" "$dmax" "$sl" "$remean" "$remax" "$vol" "$s" $((m / 1024)) >>"$tet"
  done
  PYTHON=python3  # bench/tet_quality.py needs numpy: the system Python has it (python3-numpy)
  [[ -x /usr/bin/python3 ]] && PYTHON=/usr/bin/python3
  if command -v tetgen >/dev/null; then
    "$BIN/ctsurg-surface" "$heart_grid" "$WORK/heart.ply" -q
    read -r s m < <(best_of tetgen -pYq1.414a6 -Q "$WORK/heart.ply")
    read -r nodes tets dmin dmax sl remean remax vol _ < <("$PYTHON" bench/tet_quality.py "$WORK/heart.1")
    printf '| TetGen -pYq1.414a6 (marching-cubes surface) | %s | %s | %s | %s | %s | %s / %s | %.0f | %.2f | %d |\n' \
      "$nodes" "$tets" "$dmin" "$dmax" "$sl" "$remean" "$remax" "$vol" "$s" $((m / 1024)) >>"$tet"
  else
    echo "| TetGen | not installed (\`apt-get install tetgen\`): skipped | | | | | | | | |" >>"$tet"
  fi
  splice tetmesh "$tet"
fi

# Marching cubes: ctsurg's (bench_marching_cubes, Google Benchmark, median of 5 repetitions) against
# VTK's vtkFlyingEdges3D (tests/peers/flying_edges_peer.py --time, median of 15 runs) on the same
# fields, 1 and 2 threads. VTK computes normals; ctsurg computes normals and the grid tie.
mc=$WORK/surface.md
PEER=$ROOT/tests/peers/flying_edges_peer.py
if want surface && [[ -e $WORK/heart_nifti.h5 && -e $heart_grid ]] && /usr/bin/python3 -c 'import vtk, h5py' 2>/dev/null; then
  "$BIN/ctsurg-grid" "$WORK/heart_nifti.h5" "$ROOT/data_samples/heart/heart_mask.nii.gz" "$WORK/grid_heart_1mm.h5" --voxel-mm 1.0 --no-preview -q
  {
    echo "## Mesh: marching cubes against VTK (\`bench/run.sh\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build;"
    echo "VTK $(/usr/bin/python3 -c 'import vtk; print(vtk.vtkVersion.GetVTKVersion(), "(Debian python3-vtk9, SMP backend", vtk.vtkSMPTools.GetBackend() + ")")')."
    echo "Median wall time of the isosurface extraction alone (field in memory, mesh in memory): ctsurg's"
    echo "\`marching_cubes\` (normals from the field gradient and the grid tie: cell, 8 trilinear weights and the"
    echo "nearest inside node per vertex) against \`vtkFlyingEdges3D\` with gradient normals. Nodes per second is"
    echo "the lattice size over the time. Both give the same vertex and triangle counts (docs/mesh.md)."
    echo
    echo "| field | nodes | triangles | threads | ctsurg (ms) | VTK (ms) | ctsurg nodes/s | VTK nodes/s | ctsurg / VTK speed |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
  } >"$mc"
  "$BIN/bench_marching_cubes" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true --benchmark_format=csv 2>/dev/null |
    awk -F, '/_median"?,/{gsub(/"/,"",$1); split($1,p,"/"); print p[1], p[2], $3}' >"$WORK/mc.txt"
  mc_row() {  # label bench-name field.h5 dataset iso
    local label=$1 name=$2 field=$3 dataset=$4 iso=$5
    for t in 1 2; do
      local ours vtk_json vtk_s nodes tris
      ours=$(awk -v n="$name" -v t="$t" '$1 == n && $2 == t {print $3}' "$WORK/mc.txt")
      vtk_json=$(/usr/bin/python3 "$PEER" "$field" "$dataset" "$iso" --time "$t")
      read -r vtk_s nodes tris < <(/usr/bin/python3 -c 'import json,sys; d=json.loads(sys.argv[1]); print(d["seconds"], d["nodes"], d["triangles"])' "$vtk_json")
      awk -v l="$label" -v n="$nodes" -v tr="$tris" -v t="$t" -v o="$ours" -v v="$vtk_s" 'BEGIN{
        printf "| %s | %d | %d | %d | %.2f | %.2f | %.3g | %.3g | %.2f |\n", l, n, tr, t, o, v * 1000, n / (o / 1000), n / v, v * 1000 / o}' >>"$mc"
    done
  }
  mc_row "heart CT, 150 HU" BM_MarchingCubesHeartCt150HU "$WORK/heart_nifti.h5" /hu 150
  mc_row "heart grid 2.4 mm, fraction 0.5" BM_MarchingCubesHeartGrid2_4mm "$heart_grid" /grid/fraction 0.5
  mc_row "heart grid 1.0 mm, fraction 0.5" BM_MarchingCubesHeartGrid1_0mm "$WORK/grid_heart_1mm.h5" /grid/fraction 0.5
  splice surface "$mc"
fi
# Spring-mass models: bench_spring_models (Google Benchmark, median of 5 repetitions) next to the
# spring-mass papers' Table 1 (Mosegaard & Sorensen 2005, IEEE VR; the same CPU and GPU rows in Mosegaard,
# Herborg & Sorensen 2005, MMVR).
if want sim; then
sim=$WORK/sim.md
{
  echo "## Simulation: spring-mass steps per second (\`bench/run.sh\`)"
  echo
  machine_line
  echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build."
  echo "Iterations (time steps) per second, median of 5 (\`build/bin/bench_spring_models\`): spring forces gathered per"
  echo "particle, Verlet with damping and gravity, float, 2.4 mm cells, no normals. Implicit: the 18-neighbour grid"
  echo "model; explicit: the same springs as a CSR spring list. Blocks are solid boxes; the heart is the bundled"
  echo "heart's occupancy grid at 2.4 mm (the papers' pig heart had 42,745 particles). Papers: Pentium 4 3 GHz and"
  echo "GeForce 6800 Ultra / CoolFX Ultra 2600 (Mosegaard & Sorensen 2005, Table 1; heart: 219 it/s, simulation alone,"
  echo "Mosegaard, Herborg & Sorensen 2005). Load average when the runs started: $(cut -d' ' -f1-3 /proc/loadavg) (other"
  echo "work on the machine slows the 2-thread runs most: each step waits for both threads)."
  echo
  echo "| particles | papers CPU | papers implicit GPU | papers explicit GPU | implicit, 1 thread | implicit, 2 threads | explicit, 1 thread | explicit, 2 threads |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|"
  "$BIN/bench_spring_models" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true --benchmark_format=csv 2>/dev/null |
    awk -F, '/_median"?,/{gsub(/"/,"",$1); n=split($1,p,"/"); model=p[1]; sub(/BM_/,"",model);
      if (model ~ /Heart/) {size="heart"; t=p[2]} else {size=p[2]; t=p[3]}
      kind=(model ~ /^Implicit/) ? "i" : "e"; v[size "," kind "," t]=$7; count[size]=$(NF-2)}
      END {
        paper["10000"]="45.8 | 839.8 | 457.1"; paper["20000"]="20.2 | 476.9 | 234.4"; paper["40000"]="9.9 | 264.6 | 121.0";
        paper["50000"]="7.8 | 218.0 | 99.0"; paper["100000"]="3.3 | 104.1 | 48.5"; paper["heart"]="- | 219 (42,745) | -";
        split("10000 20000 40000 50000 100000 heart", order, " ");
        for (r = 1; r <= 6; ++r) { s = order[r]; if (!(s in count)) continue;
          label = (s == "heart") ? sprintf("heart grid, %d", count[s]) : sprintf("block, %d", count[s]);
          printf "| %s | %s | %.0f | %.0f | %.0f | %.0f |\n", label, paper[s], v[s ",i,1"], v[s ",i,2"], v[s ",e,1"], v[s ",e,2"] } }'
} >"$sim"
splice sim "$sim"
fi
# Google Benchmark CSV -> a markdown table: name, real time, and the user counters.
gbench_table() { /usr/bin/python3 bench/gbench_table.py; }

# Render: bench_render (ctsurg-render's renderer, OSMesa llvmpipe): one frame at 1024 x 1024 with the
# normal map, a new deformation streamed each frame; Args = (thousands of faces... see bench_render.cpp).
if want render; then
  ren=$WORK/render.md
  {
    echo "## Render: frames per second at 1024 x 1024 (\`bench/run.sh render\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build; Mesa llvmpipe"
    echo "(OSMesa, OpenGL 4.5 core). \`build/bin/bench_render\`: a normal-mapped surface of the given face count, a new"
    echo "deformation streamed every frame; arguments (ellipsoid resolution, samples per pixel, read back). Load average"
    echo "at the start: $(cut -d' ' -f1-3 /proc/loadavg). Target: 30 frames/s for the papers' 31,320-face heart."
    echo
    "$BIN/bench_render" --benchmark_format=json 2>/dev/null | gbench_table
  } >"$ren"
  splice render "$ren"
fi

# FEM: bench_fem (static Newton solves at the FEM paper's Table 2 sizes, explicit element updates).
if want fem; then
  fem=$WORK/fem.md
  {
    echo "## FEM: static solves and explicit steps (\`bench/run.sh fem\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build."
    echo "\`build/bin/bench_fem\` (docs/fem.md explains the cases). Paper (Huang et al., Table 2, GPU): 34-62 ms per solve,"
    echo "219-1,297 ms average per deformation step at 1,018-5,071 vertices. Load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)."
    echo
    "$BIN/bench_fem" --benchmark_format=json 2>/dev/null | gbench_table
    echo
    echo "Sparse Cholesky of the linear stiffness (\`build/bin/bench_sparse_factorisation\`: why CHOLMOD, issue 16;"
    echo "one numeric factorisation per iteration, the analysis once)."
    echo
    "$BIN/bench_sparse_factorisation" --benchmark_format=json 2>/dev/null | gbench_table
  } >"$fem"
  splice fem "$fem"
fi

# Instruments: bench_instruments (the distance grid's bake, the heart step with each instrument against
# the sphere probe, the contact pass alone).
if want instruments; then
  ins=$WORK/instruments.md
  {
    echo "## Instruments: rigid meshes pushing the tissue (\`bench/run.sh instruments\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build."
    echo "\`build/bin/bench_instruments\` (docs/sim.md, \"Instruments\"): BM_Bake/k loads bundled instrument k and bakes its"
    echo "signed distance grid (once per run); BM_HeartStep/tool/threads is one step of the heart's 2.4 mm spring grid with"
    echo "no tool (0), the 5 mm sphere probe (1) or instrument k (2 + k) pressed 3 mm into the anterior wall (in_contact:"
    echo "particles it pushed when placed); BM_PushOut/N/threads is the contact pass alone over N particles spread through"
    echo "the retractor's box. Load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)."
    echo
    "$BIN/bench_instruments" --benchmark_format=json 2>/dev/null | gbench_table
  } >"$ins"
  splice instruments "$ins"
fi

# Vessel: bench_vessel (the medial-atom vessel model's step and surface, 100 to 10,000 atoms).
if want vessel; then
  ves=$WORK/vessel.md
  {
    echo "## Vessel model: a step and a surface for 100 to 10,000 atoms (\`bench/run.sh vessel\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build."
    echo "\`build/bin/bench_vessel\` (docs/vessel.md): BM_VesselStep/N is one implicit step (1/60 s, at most 6 Gauss-Newton"
    echo "iterations) of a straight vessel of N atoms 1 mm apart (r 2 mm, wall 0.4 mm, E 1 MPa) clamped at one end and sagging"
    echo "under gravity; realtime_factor is simulated seconds per wall second (1 or more: real time). BM_VesselSurface/N/S"
    echo "redraws the tube (S spokes per ring, rotation-minimising frames) from the atoms, once per output frame. One thread."
    echo "Load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)."
    echo
    "$BIN/bench_vessel" --benchmark_format=json 2>/dev/null | gbench_table
  } >"$ves"
  splice vessel "$ves"
fi

# Collision: bench_collision (the spatial hash rebuilt and queried each step, against CGAL's AABB tree and
# brute force on the same vertex-triangle queries; vertex-in-tet on a tet box).
if want collision; then
  col=$WORK/collision.md
  {
    echo "## Collision: spatial hash against CGAL's AABB tree and brute force (\`bench/run.sh collision\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build."
    echo "\`build/bin/bench_collision\`: two crossing wavy sheets of 1 mm triangles at z = 650 mm (objects 0 and 1), every"
    echo "vertex against the other object's triangles within 0.2 mm; each step builds the structure from scratch."
    echo "ns_per_primitive = time / #F (flat: linear time). CGAL: AABB tree built and queried on one thread, candidates"
    echo "checked by the same exact test; threads 0 = the library's default rule. Load average at the start:"
    echo "$(cut -d' ' -f1-3 /proc/loadavg)."
    echo
    "$BIN/bench_collision" --benchmark_format=json 2>/dev/null | gbench_table
  } >"$col"
  splice collision "$col"
fi

# The FEM paper's kidney experiment (bench/kidney_experiment.sh; needs ../shared/data/abdomen).
if want kidney && [[ -e $DATA/abdomen/upper_abdomen_ct.nii.gz ]]; then
  kid=$WORK/kidney.md
  {
    echo "## FEM paper's experiment on a kidney (\`bench/run.sh kidney\`, \`bench/kidney_experiment.sh\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d). Right kidney of the shared abdomen sample, point force, static FEM and the"
    echo "calibrated spring grid (docs/fem.md discusses the numbers)."
    echo
    bench/kidney_experiment.sh
  } >"$kid"
  splice kidney "$kid"
fi
# Time against error (issues 9 and 16; bench/time_vs_error.sh, docs/accuracy.md): every model and setting
# on the cantilever, kidney and heart scenarios against a cached quadratic Neo-Hookean reference; the
# budget tables.
if want accuracy; then
  acc=$WORK/accuracy.md
  {
    echo "## Time against error (\`bench/run.sh accuracy\`, \`bench/time_vs_error.sh\`)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d). Fastest configuration per RMS surface error budget; method, plots and"
    echo "the full CSV: docs/accuracy.md."
    if [[ -n ${TVE_OUT:-} ]]; then
      [[ -f $TVE_OUT/budgets.md ]] || { echo "bench/run.sh: no $TVE_OUT/budgets.md (run bench/time_vs_error.sh first)" >&2; exit 2; }
      echo "Tables of the run that finished $(date -u -r "$TVE_OUT/budgets.md" '+%Y-%m-%d %H:%M UTC')."
      sed -n '/^####/,$p' "$TVE_OUT/budgets.md"
    else
      bench/time_vs_error.sh "$BUILD" "$BUILD/time_vs_error" | sed -n '/^####/,$p'
    fi
  } >"$acc"
  splice accuracy "$acc"
  # The local region's rows against the full solve on the same mesh (time_vs_error's local_region.md).
  lr=${TVE_OUT:-$BUILD/time_vs_error}/local_region.md
  if [[ -f $lr ]]; then
    {
      echo "## FEM local region against the full solve (\`bench/time_vs_error.sh\`, \`LOCAL_ONLY=1\` for these rows alone)"
      echo
      machine_line
      echo "Tables of the run that finished $(date -u -r "$lr" '+%Y-%m-%d %H:%M UTC'); method: docs/fem.md, \"Local region\"."
      echo
      cat "$lr"
    } >"$WORK/local_region.md"
    splice local_region "$WORK/local_region.md"
  fi
fi
# Live sessions (issue 22): bench_live_session drives each heart model's LiveSession as ctsurg-live does
# (ticks of advance(1/60), the user's messages between them, a frame each tick) on the demo's heart
# inputs: $BUILD/demo/heart when the demo was made (make -f scripts/Makefile demo), else made here with the
# demo patient's settings (data_samples/patients/heart/patient.mk: 2.4 mm cells, tets at 6 mm), cached in
# $BUILD/bench_live/heart.
if want live; then
  heart=$BUILD/demo/heart
  if [[ ! -f $heart/grid.h5 || ! -f $heart/surface_textured.h5 || ! -f $heart/tetmesh.h5 ]]; then
    heart=$BUILD/bench_live/heart
    mkdir -p "$heart"
    [[ -f $heart/ct.h5 ]] || "$BIN/ctsurg-import" -q data_samples/heart/heart_ct.nii.gz "$heart/ct.h5"
    [[ -f $heart/grid.h5 ]] || "$BIN/ctsurg-grid" -q "$heart/ct.h5" data_samples/heart/heart_mask.nii.gz "$heart/grid.h5" \
      --voxel-mm 2.4 --label-names 1=heart
    [[ -f $heart/surface.h5 ]] || "$BIN/ctsurg-surface" -q "$heart/grid.h5" "$heart/surface.h5"
    [[ -f $heart/surface_textured.h5 ]] || "$BIN/ctsurg-normalmap" -q "$heart/surface.h5" "$heart/grid.h5" "$heart/surface_textured.h5"
    [[ -f $heart/tetmesh.h5 ]] || "$BIN/ctsurg-tetmesh" -q "$heart/grid.h5" "$heart/tetmesh.h5" --cell-size 6
  fi
  liv=$WORK/live.md
  {
    echo "## Live sessions on the heart (\`bench/run.sh live\`, issue 22)"
    echo
    machine_line
    echo "date: $(date -u +%Y-%m-%d); ctsurg $(git describe --always --dirty 2>/dev/null || echo unknown), Release build."
    echo "\`$BUILD/bin/bench_live_session\` (its header says more): each heart scenario's model as a LiveSession (the scenario"
    echo "without its \`tools:\`) on the demo's heart (2.4 mm grid, surface_textured.h5, tets at 6 mm), driven as ctsurg-live drives"
    echo "it: each tick (1/60 s of wall time) applies the client's messages that arrived (JSON through parse_live_message),"
    echo "advances the session by the simulated time owed to real time (the server's LiveClock, live_clock.h: a late tick's"
    echo "backlog caught up to 0.1 s, a quasi-static frame longer than a tick paid back by ticks that do not advance) and"
    echo "sends a picture when something changed (\`encode_live_frame(live_frame_of(...))\`). The user, in wall time: a grab"
    echo "(8 mm) at the apex's surface vertex dragged 25 mm in 3 s, a move every 1/60 s, held 0.5 s and released; then"
    echo "heart_cut's incision (20 mm edge, 40 mm) drawn in 1 s. Real-time factor = simulated s / wall s over the whole"
    echo "script (a grab's begin and each cut refactorise an FEM model: 30-300 ms); while dragging = from 0.5 s to 3 s (the"
    echo "steady drag, what the target is judged on); per-picture time = messages + advance + frame. Unpaced: the loop"
    echo "never sleeping, what the server could send. Bytes per frame: 56 + 12 V positions only, + 12 F with the triangles"
    echo "(the first frame and after a cut changed them). Steps: the engine's over the paced run (a static model: its"
    echo "nonlinear iterations, Newton or quasi-Newton). Target (issue 22): real-time factor >= 1 with"
    echo ">= 30 pictures/s on 2 cores. Load average at the start: $(cut -d' ' -f1-3 /proc/loadavg) (a shared machine)."
    echo
    "$BIN/bench_live_session" --heart "$heart" --markdown --threads 1
    "$BIN/bench_live_session" --heart "$heart" --threads 2
    echo
    echo "Load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)."
  } >"$liv"
  splice live "$liv"
fi
echo "bench/run.sh: wrote $doc"

#!/usr/bin/env bash
# tests/fuzz/make_seeds.sh BIN OUT: the seed corpus of every fuzz target, one folder per target under OUT,
# from data_samples (the heart mask, the scenarios) and from small files the release tools in BIN
# make (a phantom in each image format, and the ctsurg files of the pipeline on it). Deterministic.
set -euo pipefail
bin=$(cd "$1" && pwd)
out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"
mkdir -p "$out"/{fuzz_nifti,fuzz_nrrd,fuzz_metaimage,fuzz_dicom_folder,fuzz_scenario}
mkdir -p "$out"/{fuzz_hu_volume_file,fuzz_occupancy_grid_file,fuzz_surface_mesh_file,fuzz_tet_mesh_file,fuzz_trajectory_file,fuzz_centerline_file}
mkdir -p "$out"/{fuzz_stl,fuzz_obj,fuzz_ply}
mkdir -p "$out"/{fuzz_seg_nrrd,fuzz_vtu,fuzz_msh,fuzz_medit}
mkdir -p "$out"/fuzz_live_message
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
q="-q"

cp "$root/data_samples/heart/heart_mask.nii.gz" "$out/fuzz_nifti/heart_mask.nii.gz"
cp "$root/data_samples/scenarios/"*.yaml "$out/fuzz_scenario/"
cp "$root/data_samples/instruments/"*.stl "$out/fuzz_stl/"   # binary and ASCII STL
cp "$root/data_samples/instruments/"*.obj "$out/fuzz_obj/"
cp "$root/data_samples/instruments/"*.ply "$out/fuzz_ply/"
for suffix in nii nii.gz nrrd mha; do
  "$bin/ctsurg-phantom" $q sphere "$work/sphere.$suffix" --radius-mm 5 --spacing-mm 2 --margin-mm 2 --supersample 1
done
cp "$work/sphere.nii" "$work/sphere.nii.gz" "$out/fuzz_nifti/"
cp "$work/sphere.nrrd" "$out/fuzz_nrrd/"
cp "$work/sphere.mha" "$out/fuzz_metaimage/"

# The pipeline on a small ellipsoid shell: each stage's file is a seed of its reader.
"$bin/ctsurg-phantom" $q ellipsoid-shell "$work/shell.nii.gz" --semi-axes-mm 12,9,7 --thickness-mm 4 --spacing-mm 1.5 \
  --supersample 1
"$bin/ctsurg-import" $q "$work/shell.nii.gz" "$work/ct.h5"
"$bin/ctsurg-grid" $q "$work/ct.h5" "$work/grid.h5" --hu-min 0 --voxel-mm 3 --no-preview
"$bin/ctsurg-surface" $q "$work/grid.h5" "$work/surface.h5"
"$bin/ctsurg-tetmesh" $q "$work/grid.h5" "$work/tetmesh.h5" --cell-size 4
cat > "$work/pull.yaml" <<'YAML'
ctsurg_scenario: 1
model: {kind: spring_grid, grid: grid.h5, surface: surface.h5}
material: {preset: liver, damping_per_s: 20}
fixed: [{box_fraction: {min: [0, 0, 0], max: [0.3, 1, 1]}}]
tools:
  - grab: {radius_mm: 3, snap_to_tissue: true, path: [{t: 0, at_fraction: [1, 0.5, 0.5]}, {t: 0.01, offset_mm: [0, 0, 2]}]}
time: {duration_s: 0.02}
output: {trajectory: trajectory.h5, frame_interval_s: 0.005}
YAML
"$bin/ctsurg-sim" $q "$work/pull.yaml"
cp "$work/ct.h5" "$out/fuzz_hu_volume_file/"
cp "$work/grid.h5" "$out/fuzz_occupancy_grid_file/"
cp "$work/surface.h5" "$out/fuzz_surface_mesh_file/"
cp "$work/tetmesh.h5" "$out/fuzz_tet_mesh_file/"
cp "$work/trajectory.h5" "$out/fuzz_trajectory_file/"
cp "$work/pull.yaml" "$out/fuzz_scenario/"
# A centerline: a torus' label mask, its loop cut at the thinnest point.
"$bin/ctsurg-phantom" $q torus "$work/torus.nii.gz" --major-mm 10 --minor-mm 3 --spacing-mm 1.5 --supersample 1 \
  --label-out "$work/ring.nii.gz"
"$bin/ctsurg-centerline" $q "$work/ring.nii.gz" --break-loops -o "$work/centerline.h5"
cp "$work/centerline.h5" "$out/fuzz_centerline_file/"

# Another mesher's tet mesh in each import format: the shell's mesh exported, then converted by --import.
"$bin/ctsurg-tetmesh" $q "$work/grid.h5" "$work/shell_tets.vtu" --cell-size 4
"$bin/ctsurg-tetmesh" $q --import "$work/shell_tets.vtu" "$work/shell_tets.msh"
"$bin/ctsurg-tetmesh" $q --import "$work/shell_tets.vtu" "$work/shell_tets.mesh"
cp "$work/shell_tets.vtu" "$out/fuzz_vtu/"
cp "$work/shell_tets.msh" "$out/fuzz_msh/"
cp "$work/shell_tets.mesh" "$out/fuzz_medit/"
# 3D Slicer segmentations: one layer (raw) and two layers (gzip), 4 x 3 x 2 voxels.
python3 - "$out/fuzz_seg_nrrd" <<'PY'
import gzip, sys
def seg(layers, encoding):
    n = 4 * 3 * 2
    data = bytes((i % 3) if l == 0 else (1 if i % 5 == 0 else 0) for l in range(layers) for i in range(n))
    if layers > 1:  # NRRD's fastest axis is the list: interleave the layers
        data = bytes(data[l * n + i] for i in range(n) for l in range(layers))
    head = ["NRRD0004", "type: unsigned char", f"dimension: {3 + (layers > 1)}", "space: left-posterior-superior",
            "sizes: " + (f"{layers} " if layers > 1 else "") + "4 3 2",
            "space directions: " + ("none " if layers > 1 else "") + "(1.5,0,0) (0,1.5,0) (0,0,2)",
            "kinds: " + ("list " if layers > 1 else "") + "domain domain domain", f"encoding: {encoding}",
            "space origin: (-3,2,10)"]
    segments = [("kidney", 1, 0), ("liver", 2, 0)] + ([("vessel", 1, 1)] if layers > 1 else [])
    for k, (name, value, layer) in enumerate(segments):
        head += [f"Segment{k}_ID:={name}", f"Segment{k}_Name:={name}", f"Segment{k}_LabelValue:={value}",
                 f"Segment{k}_Layer:={layer}", f"Segment{k}_Color:=0.5 0.2 0.1", f"Segment{k}_Extent:=0 3 0 2 0 1"]
    return ("\n".join(head) + "\n\n").encode() + (gzip.compress(data, mtime=0) if encoding == "gzip" else data)
open(sys.argv[1] + "/one_layer.seg.nrrd", "wb").write(seg(1, "raw"))
open(sys.argv[1] + "/two_layers.seg.nrrd", "wb").write(seg(2, "gzip"))
PY

# The live protocol: every client message (positions on the bundled heart), and two server frames (the
# frame decoder reads the same inputs): a tetrahedron with its triangles, and its positions alone.
python3 - "$out/fuzz_live_message" <<'PY'
import struct, sys
messages = {
    "begin_grab": '{"type": "begin", "tool": "grab", "radius_mm": 8, "position_mm": [38.5, -236.25, 596], "seq": 1}',
    "begin_probe": '{"type": "begin", "tool": "probe", "radius_mm": 5, "position_mm": [20, -240, 640]}',
    "begin_cut": '{"type": "begin", "tool": "cut", "blade_edge_mm": [0, 20, 0], "position_mm": [25, -234, 615], "seq": 7}',
    "move": '{"type": "move", "id": 0, "position_mm": [41.2, -243.0, 593.3], "seq": 4294967295}',
    "end": '{"type": "end", "id": 3, "seq": 12}',
    "pause": '{"type": "pause"}',
    "resume": '{"type":"resume","seq":0}',
    "reset": '{"type": "reset"}',
    "save": '{"type": "save", "seq": 99}',
}
for name, text in messages.items():
    open(f"{sys.argv[1]}/{name}.json", "w").write(text)
def frame(flags, triangles):
    positions = [0, 0, 0, 10, 0, 0, 0, 10, 0, 0, 0, 10]
    tris = [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2]
    head = b"CTLF" + struct.pack("<HHQdqQIIII", 2, flags, 41, 0.7, 4167, 2, 4, 4, 17, 0)
    return head + struct.pack("<12f", *positions) + (struct.pack("<12I", *tris) if triangles else b"")
open(f"{sys.argv[1]}/frame_triangles.bin", "wb").write(frame(1, True))
open(f"{sys.argv[1]}/frame_positions.bin", "wb").write(frame(2, False))
PY
python3 "$root/tests/fuzz/make_dicom_seed.py" "$out/fuzz_dicom_folder/two_slices.bin"
echo "fuzz seeds: $(find "$out" -type f | wc -l) files, $(du -sk "$out" | cut -f1) KiB in $out"

#!/usr/bin/env bash
# Generates the standard synthetic phantom set (data_samples/phantoms/README.md) with ctsurg-phantom.
# Usage: scripts/make-phantoms.sh [OUT_DIR]   (default build/phantoms; the tool is taken from
# $CTSURG_BIN, default build/bin). Deterministic: rerunning gives byte-identical files.
set -euo pipefail

cd "$(dirname "$0")/.."
bin="${CTSURG_BIN:-build/bin}"
out="${1:-build/phantoms}"
tool="$bin/ctsurg-phantom"
if [[ ! -x "$tool" ]]; then
  echo "make-phantoms.sh: $tool not found; build it (ninja -C build ctsurg-phantom) or set CTSURG_BIN" >&2
  exit 2
fi
mkdir -p "$out"

"$tool" -q sphere "$out/sphere_r20.nii.gz" --radius-mm 20 --spacing-mm 0.5 \
  --label-out "$out/sphere_r20_mask.nii.gz"
"$tool" -q ellipsoid-shell "$out/ellipsoid_shell.nii.gz" --semi-axes-mm 30,22,16 --thickness-mm 4 --spacing-mm 0.5 \
  --label-out "$out/ellipsoid_shell_mask.nii.gz"
"$tool" -q torus "$out/torus.nii.gz" --major-mm 25 --minor-mm 8 --spacing-mm 0.5 \
  --label-out "$out/torus_mask.nii.gz"
"$tool" -q bumpy-sphere "$out/bumpy_sphere.nii.gz" --radius-mm 20 --bump-amplitude 0.15 --bump-m 3 --bump-n 4 \
  --spacing-mm 0.5 --label-out "$out/bumpy_sphere_mask.nii.gz"
# A clinical-like anisotropic lattice (thick slices) of the same sphere.
"$tool" -q sphere "$out/sphere_r20_ct.nii.gz" --radius-mm 20 --spacing-mm 0.7,0.7,2.5 \
  --label-out "$out/sphere_r20_ct_mask.nii.gz"

echo "make-phantoms.sh: wrote $(ls "$out" | wc -l) files to $out"

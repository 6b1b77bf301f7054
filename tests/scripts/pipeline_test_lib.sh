# Shared setup for the pipeline tests (sourced): a tiny synthetic patient made with ctsurg-phantom.
# Needs: ROOT (source tree), BIN (tools), WORK (an empty scratch folder).
set -euo pipefail
PY=${PYTHON:-/usr/bin/python3}
mk() { make --no-print-directory -f "$ROOT/scripts/Makefile" BUILD="$(dirname "$BIN")" PYTHON="$PY" "$@"; }
fail() { echo "FAIL: $*" >&2; exit 1; }

# phantom_ct DIR: a 12 mm sphere CT at 1.5 mm voxels, with its mask (seconds to build end to end).
phantom_ct() {
  mkdir -p "$1"
  "$BIN/ctsurg-phantom" -q sphere "$1/ct.nii.gz" --radius-mm 12 --spacing-mm 1.5 --label-out "$1/mask.nii.gz"
  echo "CELL_MM := 3" > "$1/patient.mk"
  echo "NORMALMAP_ARGS := --size 256" >> "$1/patient.mk"
  echo "RENDER_ARGS := --samples 1" >> "$1/patient.mk"
}

# scenario FILE KIND SURFACE RENDER: a short grab scenario. KIND spring_grid | fem | explicit_springs;
# SURFACE a stage output name or "" (none); RENDER "yes" adds one picture, "viewer" also the animated
# glTF and its HTML page.
scenario() {
  local file=$1 kind=$2 surface=$3 render=$4 stem
  stem=$(basename "${file%.yaml}")
  mkdir -p "$(dirname "$file")"
  {
    echo "ctsurg_scenario: 1"
    echo "name: $stem"
    echo "model:"
    echo "  kind: $kind"
    if [[ $kind == fem ]]; then
      echo "  tetmesh: tetmesh.h5"
      echo "  solver: static"
    else
      echo "  grid: grid.h5"
    fi
    [[ -n $surface ]] && echo "  surface: $surface"
    if [[ $kind == fem ]]; then
      echo "material: {law: linear, preset: soft_tissue, damping_per_s: 20}"
    else
      echo "material: {preset: soft_tissue, damping_per_s: 20}"
    fi
    echo "fixed:"
    echo "  - box_fraction: {min: [0, 0, 0], max: [1, 1, 0.3]}"
    echo "tools:"
    echo "  - grab:"
    echo "      radius_mm: 4"
    echo "      start_s: 0.0"
    echo "      snap_to_tissue: true"
    echo "      path:"
    echo "        - {t: 0.0, at_fraction: [0.5, 0.5, 1.0]}"
    echo "        - {t: 0.05, offset_mm: [0, 0, 2]}"
    echo "time: {duration_s: 0.1, dt_s: auto}"
    echo "output: {trajectory: $stem.h5, frame_interval_s: 0.05}"
    if [[ $render == yes || $render == viewer ]]; then
      echo "render:"
      echo "  - {name: ${stem}_picture, layout: heat-map, frames: last, size: 64}"
    fi
    [[ $render == viewer ]] && echo "  - {name: ${stem}_3d, layout: viewer}"
    true
  } > "$file"
}

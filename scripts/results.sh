#!/usr/bin/env bash
# Prints what the pipeline made for one patient and where (scripts/Makefile writes it to results.txt).
# Usage: scripts/results.sh PATIENT OUT_DIR SCENARIO...
set -euo pipefail
patient=$1 out=$2
shift 2
all=$(( $# == 0 ))   # no scenarios: every stage output made is a result
# A stage output is listed when it exists and one of this patient's scenarios reads it (an older run
# may have left others behind).
say() {
  [[ -e "$out/$1" ]] || return 0
  local needle="/$1"
  [[ $1 == surface.h5 ]] && needle="/surface"   # also the normal map's input
  case $1 in ct.h5|grid.h5|grid_preview.png|comparison.md) ;; *) ((all)) || grep -qs -- "$needle" "$out"/mk/*.mk || return 0 ;; esac
  printf '  %-32s %s\n' "$1" "$2"
}
echo "ctsurg pipeline: patient $patient, results in $out"
say ct.h5 "HU volume (ParaView: ct.xdmf)"
say grid.h5 "occupancy grid (ParaView: grid.xdmf)"
say grid_preview.png "slice montage: mask and grid outlined"
say surface.h5 "surface tied to the grid (ParaView: surface.xdmf)"
say surface_textured.h5 "surface with the baked normal map (glTF: $patient.glb, map: normal_map.png)"
say tetmesh.h5 "tetrahedral mesh (ParaView: tetmesh.xdmf)"
for s in "$@"; do
  stem=$(basename "${s%.*}")
  [[ -f "$out/mk/$stem.mk" ]] || continue
  traj=$(sed -n "s/^[^ ]*\.scenario\.$stem := //p" "$out/mk/$stem.mk")
  model=$(sed -n 's/^# model: //p' "$out/mk/$stem.mk")
  echo "  scenario $stem ($model): $s"
  printf '    %-30s %s\n' "$(basename "$traj")" "trajectory (ParaView: $(basename "${traj%.h5}").xdmf)"
  for p in $(sed -n "s/^\([^ :]*\.\(png\|frames\)\): .*/\1/p" "$out/mk/$stem.mk"); do
    printf '    %-30s %s\n' "$(basename "$p")" "picture"
  done
  for p in $(sed -n "s/^\([^ :]*\.html\) [^ ]*\.glb &: .*/\1/p" "$out/mk/$stem.mk"); do
    printf '    %-30s %s\n' "$(basename "$p")" "3D viewer: open in a browser, offline (animated glTF: $(basename "${p%.html}").glb)"
  done
done
say comparison.md "model comparison table (volume, area, displacement)"

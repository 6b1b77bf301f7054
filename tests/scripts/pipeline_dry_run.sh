#!/usr/bin/env bash
# Dry runs (make -n) per scenario kind: the pipeline runs exactly the tools the scene needs.
# Usage: pipeline_dry_run.sh ROOT BIN WORK
ROOT=$1 BIN=$2 WORK=$3
source "$(dirname "$0")/pipeline_test_lib.sh"
rm -rf "$WORK" && mkdir -p "$WORK/patients"

# One patient per scene kind, all on the same phantom CT.
for p in springs fem rendered explicit; do phantom_ct "$WORK/patients/$p"; done
scenario "$WORK/patients/springs/scenarios/springs.yaml" spring_grid surface.h5 no
scenario "$WORK/patients/fem/scenarios/fem.yaml" fem "" no
scenario "$WORK/patients/rendered/scenarios/rendered.yaml" spring_grid surface_textured.h5 viewer
scenario "$WORK/patients/explicit/scenarios/explicit.yaml" explicit_springs "" no

plan() { # plan PATIENT: the tools a dry run of that patient would run, one per line
  mk -n "$1" PATIENTS_DIR="$WORK/patients" OUT="$WORK/out" > "$WORK/$1.plan"
  grep -o 'ctsurg-[a-z]*\|compare-table\|results.sh' "$WORK/$1.plan" | sort -u | tr '\n' ' '
}
expect() { # expect PATIENT "TOOLS..." : exactly these tools
  local got want
  got=$(plan "$1")
  want=$(echo "$2" | tr ' ' '\n' | sort -u | tr '\n' ' ')
  [[ "$got" == "$want" ]] || { cat "$WORK/$1.plan" >&2; fail "$1: ran [$got], expected [$want]"; }
  echo "ok: $1 scene runs: $got"
}

# Spring grid, no pictures: no tet mesh, no normal map, no render.
expect springs "ctsurg-import ctsurg-grid ctsurg-surface ctsurg-sim results.sh"
# FEM only, no surface, no pictures: no surface, no normal map, no render. The grid stays: ctsurg-tetmesh
# meshes the grid file's full-resolution mask.
expect fem "ctsurg-import ctsurg-grid ctsurg-tetmesh ctsurg-sim results.sh"
# Rendered scene: the normal map is built and the picture rendered; still no tet mesh.
expect rendered "ctsurg-import ctsurg-grid ctsurg-surface ctsurg-normalmap ctsurg-sim ctsurg-render results.sh"
# Explicit springs from the grid without a surface: import, grid, sim only.
expect explicit "ctsurg-import ctsurg-grid ctsurg-sim results.sh"

# Only the requested outputs: the rendered scene's one picture, the right file names.
grep -q -- "-o $WORK/out/rendered/rendered_picture.png" "$WORK/rendered.plan" || fail "rendered: picture target"
grep -q -- "--surface $WORK/out/rendered/surface_textured.h5" "$WORK/rendered.plan" || fail "rendered: textured surface"
grep -q -- "--frames all --gltf $WORK/out/rendered/rendered_3d.glb --viewer $WORK/out/rendered/rendered_3d.html" \
  "$WORK/rendered.plan" || fail "rendered: the viewer's glTF and page"
grep -q -- "--tetmesh $WORK/out/fem/tetmesh.h5" "$WORK/fem.plan" || fail "fem: tet mesh passed to ctsurg-sim"
if grep -q -- "--grid" "$WORK/fem.plan"; then fail "fem: ctsurg-sim was given a grid"; fi
# The fragments are atomic and regenerated only from the scenario and the tool.
[[ -f "$WORK/out/springs/mk/springs.mk" ]] || fail "no fragment written"
ls "$WORK"/out/*/mk/*.tmp* 2>/dev/null && fail "temporary fragment left behind"

# The bundled patients plan as documented (heart_fem_grab needs the heart's tet mesh).
got=$(mk -n heart PATIENTS_DIR="$ROOT/data_samples/patients" OUT="$WORK/bundled" | grep -o 'ctsurg-[a-z]*' | sort -u | tr '\n' ' ')
[[ "$got" == "ctsurg-grid ctsurg-import ctsurg-normalmap ctsurg-render ctsurg-sim ctsurg-surface ctsurg-tetmesh " ]] || fail "heart: [$got]"
echo "ok: heart plan: $got"
# make live on a clone where the demo has not run: it builds the heart's tet mesh and textured surface
# (and the scenarios' fragments, from ctsurg-sim --describe) but simulates and renders nothing before
# ctsurg-live; it used to fail with "No rule to make target .../tetmesh.h5".
mk -n live DEMO_OUT="$WORK/live" > "$WORK/live.plan"
got=$(grep -o 'ctsurg-[a-z]*' "$WORK/live.plan" | sort -u | tr '\n' ' ')
[[ "$got" == "ctsurg-grid ctsurg-import ctsurg-live ctsurg-normalmap ctsurg-sim ctsurg-surface ctsurg-tetmesh " ]] || fail "live: [$got]"
if grep -q 'ctsurg-sim -q\|ctsurg-render' "$WORK/live.plan"; then fail "live: a scenario is simulated or rendered"; fi
echo "ok: live plan: $got"
# The batch's other patients read ../shared/data: the kidney needs the tet mesh (FEM) and the table,
# the head (a spring grid without pictures) neither a normal map nor a tet mesh nor a render, the abdomen
# the tet mesh and its pictures only.
if [[ -f "$ROOT/../shared/data/abdomen/upper_abdomen_ct.nii.gz" && -f "$ROOT/../shared/data/headsq/quarter.nhdr" ]]; then
  got=$(mk -n kidney PATIENTS_DIR="$ROOT/data_samples/patients" OUT="$WORK/bundled" | grep -o 'ctsurg-[a-z]*\|compare-table' | sort -u | tr '\n' ' ')
  [[ "$got" == "compare-table ctsurg-grid ctsurg-import ctsurg-normalmap ctsurg-render ctsurg-sim ctsurg-surface ctsurg-tetmesh " ]] || fail "kidney: [$got]"
  echo "ok: kidney plan: $got"
  got=$(mk -n head PATIENTS_DIR="$ROOT/data_samples/patients" OUT="$WORK/bundled" | grep -o 'ctsurg-[a-z]*' | sort -u | tr '\n' ' ')
  [[ "$got" == "ctsurg-grid ctsurg-import ctsurg-sim ctsurg-surface " ]] || fail "head: [$got]"
  echo "ok: head plan: $got"
  # The abdomen (two organs in contact, FEM without a surface file, with pictures): the tet mesh and the
  # pictures, drawn from the trajectory alone (no surface, no normal map, no --surface).
  got=$(mk -n abdomen PATIENTS_DIR="$ROOT/data_samples/patients" OUT="$WORK/bundled" | grep -o 'ctsurg-[a-z]*' | sort -u | tr '\n' ' ')
  [[ "$got" == "ctsurg-grid ctsurg-import ctsurg-render ctsurg-sim ctsurg-tetmesh " ]] || fail "abdomen: [$got]"
  if mk -n abdomen PATIENTS_DIR="$ROOT/data_samples/patients" OUT="$WORK/bundled" | grep ctsurg-render | grep -q -- "--surface"; then
    fail "abdomen: ctsurg-render was given a surface"
  fi
  echo "ok: abdomen plan: $got"
  # The aorta (the vessel model): its centerline from the mask, then the runs and pictures; no CT import,
  # grid, surface or tet mesh.
  got=$(mk -n aorta PATIENTS_DIR="$ROOT/data_samples/patients" OUT="$WORK/bundled" | grep -o 'ctsurg-[a-z]*' | sort -u | tr '\n' ' ')
  [[ "$got" == "ctsurg-centerline ctsurg-render ctsurg-sim " ]] || fail "aorta: [$got]"
  echo "ok: aorta plan: $got"
else
  echo "skipped: kidney, head, abdomen and aorta plans (../shared/data absent)"
fi
echo "PASS"

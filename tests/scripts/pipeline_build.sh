#!/usr/bin/env bash
# Builds a tiny synthetic patient through the pipeline (-j2), then: a rerun is a no-op (make -q and
# make -n), touching the scenario reruns only its sim and picture, and a broken patient fails alone
# under -k (reported, the others finish, no partial file).
# Usage: pipeline_build.sh ROOT BIN WORK
ROOT=$1 BIN=$2 WORK=$3
source "$(dirname "$0")/pipeline_test_lib.sh"
rm -rf "$WORK" && mkdir -p "$WORK/patients"
P=$WORK/patients
phantom_ct "$P/sphere"
scenario "$P/sphere/scenarios/pull.yaml" spring_grid surface_textured.h5 yes
scenario "$P/sphere/scenarios/still.yaml" spring_grid surface.h5 no
# A broken patient: its CT is not an image.
mkdir -p "$P/broken/scenarios" && echo "not a CT" > "$P/broken/ct.nii.gz"
cp "$P/sphere/scenarios/still.yaml" "$P/broken/scenarios/"
echo "CELL_MM := 3" > "$P/broken/patient.mk"
# A patient with one good and one broken scenario: the good one still runs.
phantom_ct "$P/badscen"
scenario "$P/badscen/scenarios/good.yaml" spring_grid surface.h5 no
printf 'ctsurg_scenario: 1\nmodel: {kind: nonsense}\n' > "$P/badscen/scenarios/bad.yaml"

args=(PATIENTS_DIR="$P" OUT="$WORK/out")
set +e
mk -k -j2 batch "${args[@]}" > "$WORK/build.log" 2>&1
rc=$?
set -e
cat "$WORK/build.log"
[[ $rc -ne 0 ]] || fail "a broken patient must make the batch fail"
grep -q "broken/ct.h5" "$WORK/build.log" || fail "the failure does not name the broken patient's file"
[[ -f "$WORK/out/sphere/results.txt" ]] || fail "the good patient did not finish under -k"
for f in pull.h5 pull_picture.png still.h5 surface_textured.h5; do
  [[ -f "$WORK/out/sphere/$f" ]] || fail "missing $f"
done
[[ ! -e "$WORK/out/sphere/tetmesh.h5" ]] || fail "a tet mesh was built that no scenario needs"
leftovers=$(find "$WORK/out/broken" -type f ! -path '*/mk/*')
[[ -z "$leftovers" ]] || fail "the broken patient left files: $leftovers"
grep -q "bad.yaml: model.kind" "$WORK/build.log" || fail "the broken scenario is not reported"
[[ -f "$WORK/out/badscen/good.h5" ]] || fail "the good scenario of a patient with a broken one did not run"
[[ ! -e "$WORK/out/badscen/results.txt" ]] || fail "a patient with a broken scenario was reported complete"
[[ ! -e "$WORK/out/badscen/mk/bad.mk" ]] || fail "a fragment was written for a broken scenario"
echo "ok: -k isolation (broken CT, broken scenario)"

# Rerun: nothing to do for the good patient.
mk -q sphere "${args[@]}" || fail "make -q says the built patient is out of date"
if mk -n sphere "${args[@]}" | grep -q "ctsurg-\|scenario-mk\|results.sh"; then fail "make -n would run something"; fi
echo "ok: rerun is a no-op"

# Touch one scenario: only its sim and picture rerun.
sleep 1
touch "$P/sphere/scenarios/pull.yaml"
ran=$(mk sphere "${args[@]}" | grep -o "^$BIN/ctsurg-[a-z]*" | xargs -n1 basename | sort | tr '\n' ' ')
[[ "$ran" == "ctsurg-render ctsurg-sim " ]] || fail "touching pull.yaml ran [$ran]"
mk -q sphere "${args[@]}" || fail "not up to date after the rebuild"
echo "ok: touching a scenario reruns only its sim and picture"
echo "PASS"

#!/usr/bin/env bash
# bench/bundled_trajectories.sh BIN PIPELINE OUT: runs every bundled scenario of the batch's patients
# (data_samples/patients/*: their patient.mk SCENARIOS or scenarios/) with BIN/ctsurg-sim on the stage
# outputs in PIPELINE/<patient>/ (grid.h5, surface*.h5, tetmesh.h5, centerline.h5: what
# `make -f scripts/Makefile -k batch OUT=PIPELINE` builds; stages that do not change between the two
# runs need building once), writing OUT/<scenario>.h5. Before and after a refactor, with the two
# builds' BIN, then bench/identical_trajectories.py BEFORE AFTER shows whether they are identical.
set -euo pipefail
BIN=$1 PIPE=$2 OUT=$3
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
mkdir -p "$OUT"
failed=0
for dir in "$ROOT"/data_samples/patients/*/; do
  patient=$(basename "$dir")
  list=$(make --no-print-directory -s -f - <<MK 2>/dev/null || true
SCENARIOS :=
SHARED_DATA := $ROOT/../shared/data
-include $dir/patient.mk
all: ; @echo \$(or \$(SCENARIOS),\$(wildcard $dir/scenarios/*.yaml))
MK
)
  for s in $list; do
    [[ $s = /* ]] || s=$dir/$s
    name=$(basename "$s" .yaml)
    inputs=$("$BIN/ctsurg-sim" --describe "$s" | /usr/bin/python3 -c 'import json,sys,os; d=json.load(sys.stdin)["inputs"]; print(" ".join(f"--{k} {os.path.basename(v)}" for k, v in d.items()))')
    opts=$(echo "$inputs" | sed "s|--\([a-z]*\) |--\1 $PIPE/$patient/|g")
    start=$(date +%s.%N)
    # shellcheck disable=SC2086
    "$BIN/ctsurg-sim" -q "$s" $opts -o "$OUT/$name.h5" >"$OUT/$name.log" 2>&1 && r=ok || { r="FAILED (see $OUT/$name.log)"; failed=$((failed + 1)); }
    awk -v n="$name" -v p="$patient" -v r="$r" -v s="$start" -v e="$(date +%s.%N)" 'BEGIN { printf "%s (%s): %s, %.1f s\n", n, p, r, e - s }'
  done
done
(( failed == 0 )) || { echo "$failed scenarios failed" >&2; exit 1; }

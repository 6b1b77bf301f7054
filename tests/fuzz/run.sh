#!/usr/bin/env bash
# tests/fuzz/run.sh [SECONDS] [TARGET...]: builds the libFuzzer targets (the 'fuzz' preset, clang), makes
# their seed corpus (tests/fuzz/make_seeds.sh, with the release tools in build/bin), and fuzzes each target
# for SECONDS (default 10), two at a time. Exit 1 when any target finds a crash, a sanitizer report,
# a leak of its refusals, a timeout (10 s for one input) or an out-of-memory (2 GiB); the inputs
# that did are in build-fuzz/findings/ and each becomes a regression test (tests/fuzz/README.md).
# CI runs it for 6 s a target after the release suite; bench/fuzz.sh runs it for longer.
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-10}
shift || true
# CTSURG_FUZZ_OPT: the targets' optimisation (default -O1, the preset's). CI builds them at -O0: 165 s
# instead of 257 s on 2 cores, for fewer runs a second in its short run (docs/architecture.md).
opt=${CTSURG_FUZZ_OPT:--O1}
cmake --preset fuzz -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$opt -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="$opt -g1 -DNDEBUG" >/dev/null
cmake --build --preset fuzz
[[ -x build/bin/ctsurg-phantom && -x build/bin/ctsurg-centerline ]] || scripts/build.sh
tests/fuzz/make_seeds.sh build/bin build-fuzz/seeds
targets=("$@")
if ((${#targets[@]} == 0)); then
  targets=(fuzz_nifti fuzz_nrrd fuzz_metaimage fuzz_dicom_folder fuzz_scenario fuzz_hu_volume_file
           fuzz_occupancy_grid_file fuzz_surface_mesh_file fuzz_tet_mesh_file fuzz_trajectory_file fuzz_centerline_file fuzz_stl fuzz_obj fuzz_ply
           fuzz_seg_nrrd fuzz_vtu fuzz_msh fuzz_medit fuzz_live_message)
fi
mkdir -p build-fuzz/findings build-fuzz/logs
# Third-party leaks on error paths are suppressed (tests/fuzz/lsan.supp says which and why).
export LSAN_OPTIONS="suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1"
run_one() {
  local t=$1 seconds=$2
  mkdir -p "build-fuzz/corpus/$t"
  local dict=()  # a target's dictionary of tokens, when it has one (tests/fuzz/<target>.dict)
  [[ -f tests/fuzz/$t.dict ]] && dict=(-dict="tests/fuzz/$t.dict")
  # The corpus grows across runs (kept in build-fuzz/corpus); the seeds are read-only inputs.
  if build-fuzz/bin/"$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 "${dict[@]}" \
       -artifact_prefix="build-fuzz/findings/$t-" "build-fuzz/corpus/$t" "build-fuzz/seeds/$t" \
       >"build-fuzz/logs/$t.log" 2>&1; then
    echo "$t: $(grep -o 'stat::number_of_executed_units: [0-9]*' "build-fuzz/logs/$t.log" | grep -o '[0-9]*$') runs, no finding"
  else
    echo "$t: FINDING (build-fuzz/logs/$t.log)"
    grep -m3 -E "ERROR|SUMMARY|terminate|uncaught" "build-fuzz/logs/$t.log" || true
    return 1
  fi
}
export -f run_one
printf '%s\n' "${targets[@]}" | xargs -P 2 -I{} bash -c 'run_one {} '"$seconds"

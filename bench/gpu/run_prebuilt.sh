#!/usr/bin/env bash
# On a GPU machine without ctsurg's Debian packages: runs what bench/gpu/pack_prebuilt.sh packed (the gpu
# tests, compute-sanitizer on the device tests, the live sessions of the bundled heart on the CPU and
# on CUDA, the device benchmarks) and writes each one's log to OUT. Prints a pass/fail line per step.
#
#   bench/gpu/run_prebuilt.sh PACK OUT        (from the repository root: the scenarios are read there)
#
# Exit status: non-zero when a step failed; every step runs regardless, each under a time limit.
set -uo pipefail
[[ $# -eq 2 ]] || { sed -n 2,8p "$0" >&2; exit 2; }
pack=$(cd "$1" && pwd) out=$2
mkdir -p "$out"
if [[ -f $pack/pack.tar.xz ]]; then
  mkdir -p /tmp/ctsurg-pack && tar -C /tmp/ctsurg-pack -xJf "$pack/pack.tar.xz" && pack=/tmp/ctsurg-pack
fi
export LD_LIBRARY_PATH=$pack/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.memory --format=csv | tee "$out/nvidia-smi.txt"
status=0
step() {  # step NAME SECONDS COMMAND...
  local name=$1 limit=$2
  shift 2
  local t0=$SECONDS
  if timeout "$limit" "$@" >"$out/$name.log" 2>&1; then
    echo "$name: pass ($((SECONDS - t0)) s)"
  else
    echo "$name: FAIL, status $? ($((SECONDS - t0)) s)"
    status=1
  fi
  grep -E "PASSED|FAILED|SKIPPED|ERROR SUMMARY|\| " "$out/$name.log" | tail -n 12
}
# test_sim_gpu holds every gpu test (DeviceSimulationTest, FemDeviceTest, CollisionDeviceTest, ScenarioGpu);
# test_sim's Backend tests check what the device reports.
step test_backend 180 "$pack/bin/test_sim" --gtest_brief=1 --gtest_filter='Backend.*'
step test_sim_gpu 300 "$pack/bin/test_sim_gpu" --gtest_brief=1
# No gpu test may be skipped here: a skip means the device was not found.
if grep -h "SKIPPED \] [A-Za-z]*\." "$out"/test_*.log | grep -qv "WithoutADevice"; then echo "a gpu test was skipped: the device was not seen"; status=1; fi
for backend in cuda cpu; do
  step "live-$backend" 200 "$pack/bin/bench_live_session" --heart "$pack/heart" --scenarios data_samples/scenarios \
    --cases grid,explicit,fem_dynamic --threads 1 --backend "$backend" --markdown
done
step bench_device_simulation 120 "$pack/bin/bench_device_simulation" --benchmark_min_time=0.1
step bench_fem_device 120 "$pack/bin/bench_fem_device" --benchmark_min_time=0.1
sanitizer=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
for tool in memcheck racecheck synccheck; do
  step "$tool-test_device_simulation" 120 "$sanitizer" --tool "$tool" --error-exitcode 1 "$pack/bin/test_sim_gpu" --gtest_brief=1 --gtest_filter='DeviceSimulationTest.*'
done
step memcheck-test_fem_device 120 "$sanitizer" --tool memcheck --error-exitcode 1 "$pack/bin/test_sim_gpu" --gtest_brief=1 --gtest_filter='FemDeviceTest.*'
exit $status

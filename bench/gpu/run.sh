#!/usr/bin/env bash
# One command on a machine with a CUDA GPU (docs/gpu.md): builds ctsurg with CUDA, runs the gpu tests
# (CPU vs GPU agreement: spring models, scenarios, the FEM's explicit step and static CG), the device
# tests under compute-sanitizer memcheck, racecheck and synccheck, the bundled heart's scenarios through
# the pipeline on both backends (compared frame by frame), and the DeviceSimulation and FEM device
# benchmarks, and writes a markdown report for docs/benchmarks.md. Needs the Debian packages of
# scripts/install-deps.sh (h5py for the comparison) and the CUDA toolkit with compute-sanitizer.
#
#   bench/gpu/run.sh [build-dir]        (default build-gpu; report in <build-dir>/gpu-report.md)
#
# Environment: CUDA_ARCHS (default "native": the GPU of this machine; e.g. "80;86;89;90"), JOBS
# (default: all cores), BENCH_MIN_TIME (Google Benchmark min time per case in seconds, default 0.5).
# Exit status: non-zero when a step fails (the report says which); every step runs regardless.
set -uo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build-gpu}
archs=${CUDA_ARCHS:-native}
jobs=${JOBS:-$(nproc)}
min_time=${BENCH_MIN_TIME:-0.5}
report="$build/gpu-report.md"
status=0

step() {  # step <name> <command...>: runs, logs to $build/<name>.log, records pass/fail
  local name=$1; shift
  echo "== $name: $*" >&2
  if "$@" >"$build/$name.log" 2>&1; then results+=("| $name | pass |"); else results+=("| $name | **FAIL** (see $build/$name.log) |"); status=1; fi
  tail -n 5 "$build/$name.log" >&2
}

mkdir -p "$build"
results=()
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.memory --format=csv >"$build/nvidia-smi.txt" 2>&1 || true
step configure cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCTSURG_CUDA=ON -DCTSURG_HTML_VIEWER=OFF \
  "-DCMAKE_CUDA_ARCHITECTURES=$archs"
step build cmake --build "$build" -j "$jobs" --target test_sim_gpu test_sim ctsurg-sim bench_device_simulation bench_fem_device \
  ctsurg-import ctsurg-grid ctsurg-surface ctsurg-normalmap ctsurg-tetmesh ctsurg-render
step tests-gpu ctest --test-dir "$build" -L gpu --output-on-failure --no-tests=error
step tests-cpu-kernels ctest --test-dir "$build" -L unit -R 'Backend|SpringMassStep|ExplicitSpring|SphereTools|SpringCutting|SurfaceCoupling|FemExplicitDynamics|FemStaticSolver' --output-on-failure
# No test may be skipped here: the GPU is present, so a skip means the device was not found.
step no-skips bash -c "! grep -q 'Skipped' '$build/tests-gpu.log'"
if command -v compute-sanitizer >/dev/null 2>&1; then
  sanitizer=compute-sanitizer
elif [ -x /usr/local/cuda/bin/compute-sanitizer ]; then
  sanitizer=/usr/local/cuda/bin/compute-sanitizer
else
  sanitizer=""
fi
if [ -n "$sanitizer" ]; then
  # The device tests of test_sim_gpu: the spring models' (DeviceSimulationTest) and the FEM's (FemDeviceTest).
  for suite in DeviceSimulationTest FemDeviceTest; do
    for tool in memcheck racecheck synccheck; do
      leak=(); [[ $tool == memcheck ]] && leak=(--leak-check full)
      step "$tool-$suite" "$sanitizer" --tool "$tool" --error-exitcode 1 "${leak[@]}" "$build/bin/test_sim_gpu" "--gtest_filter=$suite.*"
    done
  done
else
  results+=("| compute-sanitizer | **not found** |"); status=1
fi
# The bundled heart's scenarios (data_samples/scenarios/heart_*.yaml: spring grid and explicit springs
# with grabs, two retractors, a probe and a cut; Neo-Hookean FEM) through the pipeline on both
# backends from the same files, compared frame by frame.
step heart-cpu make -f scripts/Makefile -j"$jobs" demo "BUILD=$build" "DEMO_OUT=$build/heart-cpu" "SIM_ARGS=--backend cpu"
step heart-cuda make -f scripts/Makefile -j"$jobs" demo "BUILD=$build" "DEMO_OUT=$build/heart-cuda" "SIM_ARGS=--backend cuda"
step heart-compare python3 bench/gpu/compare_trajectories.py "$build/heart-cpu" "$build/heart-cuda"
step bench "$build/bin/bench_device_simulation" --benchmark_format=console --benchmark_out_format=json \
  "--benchmark_out=$build/bench_device_simulation.json" "--benchmark_min_time=${min_time}"
step bench-fem "$build/bin/bench_fem_device" --benchmark_format=console --benchmark_out_format=json \
  "--benchmark_out=$build/bench_fem_device.json" "--benchmark_min_time=${min_time}"

{
  echo "## GPU: DeviceSimulation and the FEM (bench/gpu/run.sh, $(date -u +%Y-%m-%d))"
  echo
  echo '```'
  cat "$build/nvidia-smi.txt"
  head -n 1 "$build/bench.log"
  echo '```'
  echo
  echo "| check | result |"
  echo "|---|---|"
  printf '%s\n' "${results[@]}"
  echo
  if [ -s "$build/heart-compare.log" ]; then
    echo "The heart scenarios, cpu against cuda (bench/gpu/compare_trajectories.py):"
    echo
    cat "$build/heart-compare.log"
    echo
  fi
  if [ -s "$build/bench_device_simulation.json" ]; then
    python3 - "$build/bench_device_simulation.json" <<'PY'
import json, sys
data = json.load(open(sys.argv[1]))
print("| model | particles | iterations/s | particle updates/s | B/particle/step | GB/s | of peak |")
print("|---|---:|---:|---:|---:|---:|---:|")
for b in data["benchmarks"]:
    if b.get("run_type") == "aggregate":
        continue
    model = "grid (implicit)" if "Grid" in b["name"] else "explicit (CSR)"
    peak = b.get("peak_GB/s", 0)
    frac = f'{100 * b["GB/s"] / peak:.0f}%' if peak else "n/a"
    print(f'| {model} | {int(b["particles"]):,} | {b["items_per_second"]:,.0f} | {b["particle_updates/s"]:.3g} | '
          f'{b["bytes_per_particle"]:.0f} | {b["GB/s"]:.0f} | {frac} |')
print()
print("Targets (issue 6): 100k particles >= 50,000 iterations/s; 10M particles >= 60% of the peak bandwidth "
      "with the bytes per particle per step stated in bench/bench_device_simulation.cpp.")
PY
  fi
  if [ -s "$build/bench_fem_device.json" ]; then
    echo
    python3 - "$build/bench_fem_device.json" <<'PY'
import json, sys
runs = [b for b in json.load(open(sys.argv[1]))["benchmarks"] if b.get("run_type") != "aggregate"]
print("FEM explicit step on the device (Neo-Hookean, bench/bench_fem_device.cpp):")
print()
print("| tets | steps/s | element updates/s | B/element/step | GB/s | of peak |")
print("|---:|---:|---:|---:|---:|---:|")
for b in runs:
    if "Explicit" not in b["name"]:
        continue
    peak = b.get("peak_GB/s", 0)
    frac = f'{100 * b["GB/s"] / peak:.0f}%' if peak else "n/a"
    print(f'| {int(b["tets"]):,} | {b["items_per_second"]:,.0f} | {b["element_updates/s"]:.3g} | '
          f'{b["bytes_per_element"]:.0f} | {b["GB/s"]:.0f} | {frac} |')
print()
print("Static linear solve, Jacobi CG (cube of n^3 cells, top centre grabbed 2 mm; bench_fem's static_solve):")
print()
print("| vertices | tets | backend | solve ms | Newton its | CG its | CG ms | assembly ms |")
print("|---:|---:|---|---:|---:|---:|---:|---:|")
for b in runs:
    if "Static" not in b["name"]:
        continue
    print(f'| {int(b["vertices"]):,} | {int(b["tets"]):,} | {b.get("label", "")} | {b["real_time"]:.1f} | '
          f'{int(b["newton_its"])} | {int(b["cg_its"])} | {b["cg_ms"]:.1f} | {b["assembly_ms"]:.1f} |')
PY
  fi
} >"$report"
cat "$report"
echo "report: $report" >&2
exit $status

#!/usr/bin/env bash
# Installs everything ctsurg needs on Debian 12 (bookworm) from Debian's own packages.
# Safe to rerun; uses sudo only when not already root. CTSURG_SKIP_APT=1 skips it (packaged builds).
set -euo pipefail
[[ "${CTSURG_SKIP_APT:-0}" == 1 ]] && exit 0

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git
  # libraries (docs/architecture.md says which stage uses which)
  libeigen3-dev libhdf5-dev libinsighttoolkit5-dev libgdcm-dev libopencv-dev libcgal-dev libassimp-dev
  libosmesa6-dev libcli11-dev libspdlog-dev nlohmann-json3-dev libyaml-cpp-dev libssl-dev zlib1g-dev
  # fuzzing: clang with libFuzzer and the sanitizer runtimes (tests/fuzz/README.md)
  clang libclang-rt-14-dev
  # the FEM's sparse Cholesky (CHOLMOD) and the BLAS it runs on (OpenBLAS over Debian's reference BLAS);
  # libblas-dev's libblas.so links the quasi-Newton's single-precision substitutions (sparse_cholesky.h)
  libsuitesparse-dev libopenblas0-pthread libblas-dev
  # tests and benchmarks; dcm2niix, python3-nibabel/vtk9 and tetgen are the peers we validate against
  libgtest-dev libgmock-dev libbenchmark-dev dcm2niix libgdcm-tools python3 python3-numpy python3-nibabel
  python3-vtk9 python3-h5py time tetgen
  # the pipeline's scale-out path (scripts/Snakefile, docs/pipeline.md) and its test
  snakemake
  # video: ctsurg-render --animation .gif/.mp4 (H.264) and ffprobe in its tests
  ffmpeg
  # npm packages (below): the Khronos glTF validator the tests run on every .glb/.gltf, and the HTML
  # viewer that ctsurg-render --viewer embeds at build time
  nodejs npm
  # ctsurg-live's web server: Boost.Beast (HTTP and WebSocket, header-only) on Boost.Asio
  libboost-dev
  # the browser the HTML viewer's test opens (headless, WebGL on the CPU through SwiftShader)
  chromium
)

# The folders with a package.json and a pinned package-lock.json: tests/support/gltf (gltf-validator),
# render/viewer (@google/model-viewer, read by render/CMakeLists.txt at build time), sim/live/page
# (three.js for ctsurg-live's page, read by sim/live/CMakeLists.txt at build time).
npm_folders=(tests/support/gltf render/viewer sim/live/page)

# npm ci in each npm folder, only when its node_modules is missing or was installed from another lock:
# reruns stay offline.
install_npm_packages() {
  local root folder dir lock stamp
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  for folder in "${npm_folders[@]}"; do
    dir="$root/$folder"
    lock="$(sha256sum "$dir/package-lock.json" | cut -d' ' -f1)"
    stamp="$dir/node_modules/.ctsurg-lock.sha256"
    [[ -f "$stamp" && "$(cat "$stamp")" == "$lock" ]] && continue
    echo "install-deps: npm ci in $dir"
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
    echo "$lock" >"$stamp"
  done
}

missing=()
for p in "${packages[@]}"; do
  [[ $p == npm ]] && command -v npm >/dev/null && continue  # NodeSource's nodejs bundles npm
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  install_npm_packages
  exit 0
fi
SUDO=""
[[ $(id -u) -ne 0 ]] && SUDO="sudo"
echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
install_npm_packages
echo "install-deps: done"

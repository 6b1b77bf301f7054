#!/usr/bin/env bash
# Packs a CUDA build made here for a GPU machine that has the NVIDIA driver and CUDA but none of
# ctsurg's Debian packages (the lent device machines): the gpu tests, the GPU benchmarks and
# ctsurg-sim, stripped, with every shared library they load that is not the C library or the driver,
# and the bundled heart's demo inputs, as OUT/pack.tar.xz. bench/gpu/run_prebuilt.sh runs them there.
#
#   bench/gpu/pack_prebuilt.sh BUILD HEART_DIR OUT      e.g. build-cuda build/demo/heart build-gpu-carry
#
# BUILD: configured with -DCTSURG_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 (the device's) and these targets
# built: test_sim (for its Backend tests) test_sim_gpu bench_device_simulation bench_fem_device
# bench_live_session ctsurg-sim.
# BLAS: the reference BLAS and LAPACK go instead of OpenBLAS (a tenth of the size; CHOLMOD's speed
# there is not what the GPU run measures).
set -euo pipefail
[[ $# -eq 3 ]] || { sed -n 2,12p "$0" >&2; exit 2; }
build=$1 heart=$2 out=$3
programs=(test_sim test_sim_gpu bench_device_simulation bench_fem_device bench_live_session ctsurg-sim)
rm -rf "$out"
mkdir -p "$out/bin" "$out/lib" "$out/heart"
for p in "${programs[@]}"; do
  [[ -x $build/bin/$p ]] || { echo "pack_prebuilt: $build/bin/$p is missing: build it first" >&2; exit 1; }
  strip --strip-unneeded -o "$out/bin/$p" "$build/bin/$p"
done
# Shared libraries: all but the C library, the dynamic loader and the driver (libcuda comes from the
# device's driver; libcudart from here, the same CUDA 13.0).
ldd "${programs[@]/#/$build/bin/}" | awk '/=> \// {print $3}' | sort -u |
  grep -Ev '/(libc|libm|libdl|librt|libpthread|ld-linux-x86-64|libcuda)\.so' | while read -r lib; do
    case $lib in
      */libblas.so.3) cp -L /usr/lib/x86_64-linux-gnu/blas/libblas.so.3 "$out/lib/" ;;
      */liblapack.so.3) cp -L /usr/lib/x86_64-linux-gnu/lapack/liblapack.so.3 "$out/lib/" ;;
      */libopenblas.so.0) ;;  # loaded only by OpenBLAS's libblas and liblapack, replaced above
      *) cp -L "$lib" "$out/lib/" ;;
    esac
  done
strip --strip-unneeded "$out"/lib/*.so* 2>/dev/null || true
cp "$heart"/grid.h5 "$heart"/surface.h5 "$heart"/surface_textured.h5 "$heart"/tetmesh.h5 "$out/heart/"
# One compressed file travels (the device tool's size limit); run_prebuilt.sh unpacks it.
tar -C "$out" -cJf "$out.tar.xz" .
rm -rf "$out"
mkdir -p "$out"
mv "$out.tar.xz" "$out/pack.tar.xz"
du -sh "$out/pack.tar.xz"

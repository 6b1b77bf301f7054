#!/usr/bin/env python3
"""The live drag's error table (bench/live_drag_error.sh): each case's surface against the reference's,
frame by frame, and its nonlinear iterations a frame (the trajectory's newton_iterations metric); for
the quasi-Newton cases the solver's own per-frame estimate of its error (the metric solver_error_mm,
what the live page shows) against the measured one, the largest over the surface's vertices.

    live_drag_error.py OUT      (OUT holds reference.h5 and the cases' NAME.h5, NAME.yaml, NAME.time)
"""
import pathlib
import sys

import h5py
import numpy as np

LABELS = {
    "live": "heart_live.yaml's solver (quasi-Newton to 0.05 mm, the extrapolated start)",
    "qn_0.02": "quasi-Newton to 0.02 mm",
    "qn_0.01": "quasi-Newton to 0.01 mm",
    "newton_0.05": "Newton to 0.05 mm",
    "linear": "linear FEM (the live default before issue 32)",
}


def surface(path):
    with h5py.File(path, "r") as f:
        t = f["/trajectory"]
        v = t["surface/vertices"][:].astype(np.float64)
        iterations = estimate = None
        if "metrics" in t and "newton_iterations" in t["metrics"]:
            iterations = t["metrics/newton_iterations"][:].astype(np.float64)
        if "metrics" in t and "solver_error_mm" in t["metrics"]:
            estimate = t["metrics/solver_error_mm"][:].astype(np.float64)
    return v, iterations, estimate


def main():
    out = pathlib.Path(sys.argv[1])
    ref, _, _ = surface(out / "reference.h5")
    estimates = []
    print("| model (same mesh, same drag) | RMS over the surface, worst frame (mm) | at the end (mm) | max, any vertex and frame (mm) | nonlinear iterations a frame | run (s) |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, label in LABELS.items():
        path = out / f"{name}.h5"
        if not path.exists():
            continue
        v, iterations, estimate = surface(path)
        if v.shape != ref.shape:
            sys.exit(f"live_drag_error.py: {path}: surface {v.shape} against the reference's {ref.shape}")
        d = np.linalg.norm(v - ref, axis=2)  # frames x vertices
        rms = np.sqrt((d**2).mean(axis=1))
        its = f"{np.mean(iterations[1:]):.1f}" if iterations is not None and len(iterations) > 1 else "-"
        seconds = (out / f"{name}.time").read_text().split()[-1] if (out / f"{name}.time").exists() else "-"
        print(f"| {label} | {rms.max():.3f} | {rms[-1]:.3f} | {d.max():.3f} | {its} | {seconds} |")
        if estimate is not None:
            estimates.append((label, estimate, d.max(axis=1)))
    if estimates:
        print()
        print("The solver's own estimate (metric solver_error_mm: the next L-BFGS step's largest nodal displacement) against the")
        print("measured error (the largest over the surface's vertices), frame by frame, over the frames where the measured error")
        print("is above 0.005 mm:")
        print()
        print("| model | frames | measured, worst frame (mm) | estimate, worst frame (mm) | estimate / measured: median, 5th, 95th percentile |")
        print("|---|---:|---:|---:|---:|")
        for label, estimate, truth in estimates:
            keep = truth > 0.005
            ratio = estimate[keep] / truth[keep]
            q = np.percentile(ratio, [50, 5, 95]) if ratio.size else [np.nan] * 3
            print(f"| {label} | {int(keep.sum())} | {truth.max():.3f} | {estimate.max():.3f} | {q[0]:.2f}, {q[1]:.2f}, {q[2]:.2f} |")


if __name__ == "__main__":
    main()

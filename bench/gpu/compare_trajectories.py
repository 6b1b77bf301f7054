#!/usr/bin/env python3
"""Frame-by-frame comparison of the same scenarios run on two backends (bench/gpu/run.sh).

    compare_trajectories.py CPU_DIR CUDA_DIR [--tolerance MM]

For every trajectory (*.h5 with /trajectory) in CPU_DIR that CUDA_DIR also has: the largest surface
vertex difference over all frames and in the last frame (mm), whether the surface topology (cuts)
is the same in every frame, and the frame count. Prints a Markdown table; exits 1 when a pair differs
by more than the tolerance (default 0.05 mm), has different topologies or frame counts, or when no
pair was found. Needs h5py and numpy (Debian python3-h5py).
"""
import argparse
import pathlib
import sys

import h5py
import numpy as np


def load(path):
    with h5py.File(path, "r") as f:
        if "trajectory" not in f:
            return None
        t = f["trajectory"]
        surface = t["surface"]
        topologies = [np.asarray(surface["topologies"][k]) for k in sorted(surface["topologies"], key=int)]
        model = t.attrs.get("model", "")
        return {
            "model": model.decode() if isinstance(model, bytes) else str(model),
            "vertices": np.asarray(surface["vertices"], dtype=np.float64),
            "topology_of_frame": np.asarray(surface["topology_of_frame"]),
            "topologies": topologies,
        }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cpu_dir", type=pathlib.Path)
    ap.add_argument("cuda_dir", type=pathlib.Path)
    ap.add_argument("--tolerance", type=float, default=0.05, help="largest allowed vertex difference, mm")
    a = ap.parse_args()
    rows, failed = [], False
    for cpu_path in sorted(a.cpu_dir.glob("*.h5")):
        cuda_path = a.cuda_dir / cpu_path.name
        if not cuda_path.exists():
            continue
        c, g = load(cpu_path), load(cuda_path)
        if c is None or g is None:
            continue
        same_frames = c["vertices"].shape == g["vertices"].shape
        same_topology = (np.array_equal(c["topology_of_frame"], g["topology_of_frame"]) and len(c["topologies"]) == len(g["topologies"])
                         and all(np.array_equal(x, y) for x, y in zip(c["topologies"], g["topologies"])))
        if same_frames:
            d = np.linalg.norm(c["vertices"] - g["vertices"], axis=-1)
            worst, last = float(d.max()), float(d[-1].max())
        else:
            worst = last = float("nan")
        ok = same_frames and same_topology and worst <= a.tolerance
        failed |= not ok
        rows.append(f"| {cpu_path.stem} | {c['model']} | {c['vertices'].shape[0]} | {worst:.3g} | {last:.3g} | "
                    f"{'same' if same_topology else '**differs**'} | {'pass' if ok else '**FAIL**'} |")
    if not rows:
        print(f"no trajectory pairs in {a.cpu_dir} and {a.cuda_dir}", file=sys.stderr)
        return 1
    print(f"| scenario | model | frames | max vertex difference (mm) | last frame (mm) | topology | within {a.tolerance} mm |")
    print("|---|---|---:|---:|---:|---|---|")
    print("\n".join(rows))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

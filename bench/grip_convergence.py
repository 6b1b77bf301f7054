#!/usr/bin/env python3
"""The tables of bench/grip_convergence.sh: for each grip, the surface's displacement at the drag's end
compared between consecutive levels (RMS and max over the shared surface's vertices, mm), the grab's pull
(N, the trajectory's sphere_loads), and from three levels an observed order p and a Richardson estimate of
the finest level's own error: with e(h) = C h^p, d_12 = C (h_1^p - h_2^p) and d_23 = C (h_2^p - h_3^p) give p
(bisection on their ratio) and e_3 = d_23 h_3^p / (h_2^p - h_3^p).

    grip_convergence.py OUT MID H1 H2 H3 ...     (MID: the level of the radius runs; the levels' h, coarsest first)

and for the radius runs at MID (radius 7.75 and 8.25 against 8 mm), the same comparison.

Needs h5py and numpy (Debian python3-h5py)."""
import math
import sys

import h5py
import numpy as np


def load(path):
    with h5py.File(path, "r") as f:
        t = f["/trajectory"]
        rest = t["surface/rest_vertices"][:].astype(np.float64)
        last = t["surface/vertices"][-1].astype(np.float64)
        loads = t["tools/sphere_loads"][-1, 0] if "sphere_loads" in t["tools"] else None
    return last - rest, loads


def order(d12, d23, h1, h2, h3):
    """p with (h1^p - h2^p) / (h2^p - h3^p) = d12 / d23, or None when the differences do not shrink."""
    if not (d12 > 0 and d23 > 0) or d23 >= d12 * (h2 / h1):
        return None
    target = d12 / d23
    lo, hi = 1e-3, 12.0
    ratio = lambda p: (h1**p - h2**p) / (h2**p - h3**p)
    if not (ratio(lo) <= target <= ratio(hi)):
        return None
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if ratio(mid) < target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def change(a, b):
    d = np.linalg.norm(a - b, axis=1)
    return float(np.sqrt(np.mean(d**2))), float(np.percentile(d, 95)), float(d.max())


def seconds(path):
    with open(path) as f:
        kib, secs = f.read().split()
    return float(secs), int(kib) // 1024


def main():
    out, mid, levels = sys.argv[1], sys.argv[2], sys.argv[3:]
    hs = [float(v) for v in levels]
    print("| grip | from h | to h | RMS change (mm) | 95th percentile (mm) | max (mm) | pull at the finer level (N) | wall, finer level (s) | peak memory (MiB) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    summary = []
    for grip in ("nodes", "volume"):
        u, pulls, rms = [], [], []
        for v in levels:
            d, l = load(f"{out}/v{v}_{grip}.h5")
            u.append(d)
            pulls.append(None if l is None or l[0] != 1 else float(np.linalg.norm(l[1:4])))
        for k in range(1, len(levels)):
            r, p95, mx = change(u[k], u[k - 1])
            rms.append(r)
            secs, mib = seconds(f"{out}/v{levels[k]}_{grip}.time")
            pull = "-" if pulls[k] is None else f"{pulls[k]:.4f}"
            print(f"| {grip} | {levels[k-1]} | {levels[k]} | {r:.3f} | {p95:.3f} | {mx:.3f} | {pull} | {secs:.0f} | {mib} |")
        if len(levels) >= 3:
            p = order(rms[-2], rms[-1], hs[-3], hs[-2], hs[-1])
            if p is None:
                summary.append(f"- grip {grip}: the changes do not shrink fast enough ({rms[-2]:.3f} then {rms[-1]:.3f} mm RMS): no Richardson estimate")
            else:
                e = rms[-1] * hs[-1] ** p / (hs[-2] ** p - hs[-1] ** p)
                fp = ""
                if None not in pulls[-3:]:
                    f12, f23 = abs(pulls[-2] - pulls[-3]), abs(pulls[-1] - pulls[-2])
                    q = order(f12, f23, hs[-3], hs[-2], hs[-1])
                    if q is not None:
                        fe = f23 * hs[-1] ** q / (hs[-2] ** q - hs[-1] ** q)
                        fp = f"; the pull {pulls[-1]:.4f} N, order {q:.2f}, its own error about {fe:.4f} N ({100 * fe / pulls[-1]:.1f} %)"
                    else:
                        fp = f"; the pull {pulls[-3]:.4f}, {pulls[-2]:.4f}, {pulls[-1]:.4f} N (its changes do not shrink fast enough for an estimate)"
                summary.append(f"- grip {grip}: observed order {p:.2f}; the h {levels[-1]} surface's own error about {e:.3f} mm RMS (Richardson){fp}")
    print()
    print("\n".join(summary))
    print()
    print(f"The radius moved by 0.25 mm at h {mid}:")
    print()
    print("| grip | radius (mm) | RMS change from 8 mm (mm) | 95th percentile (mm) | max (mm) | pull (N) |")
    print("|---|---:|---:|---:|---:|---:|")
    for grip in ("nodes", "volume"):
        base, bl = load(f"{out}/v{mid}_{grip}.h5")
        print(f"| {grip} | 8 | - | - | - | {np.linalg.norm(bl[1:4]):.4f} |")
        for r in ("7.75", "8.25"):
            d, l = load(f"{out}/v{mid}_{grip}_r{r}.h5")
            c = change(d, base)
            print(f"| {grip} | {r} | {c[0]:.3f} | {c[1]:.3f} | {c[2]:.3f} | {np.linalg.norm(l[1:4]):.4f} |")


if __name__ == "__main__":
    main()

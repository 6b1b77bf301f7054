#!/usr/bin/env python3
"""The live heart's discretisation error from nested refinements (bench/nested_convergence.sh).

    nested_convergence.py OUT      (OUT holds mesh0.h5 and the cases' NAME.h5 and NAME.time)

For each grip (volume, nodes) the P1 sequence on the 6 mm mesh refined 0, 1 and 2 times gives, at each
compared time, the RMS change of the surface between levels (d01, d12), the observed order
p = log2(d01 / d12), and the Richardson extrapolation u* = u2 + (u2 - u1) / (2^p - 1) vertex by vertex,
whose own error is estimated as |u* - u2| / (2^p - 1) (the next level's change, were the order to
hold). The reference is the volume grip's u*. Every case's distance from it follows: RMS over the
surface's vertices, the largest, and the same over the vertices that lie inside the 6 mm mesh (the
others, 54 % of the textured surface, follow the nearest tet's field extended linearly). The P2 pair
(6 and 3 mm, volume grip) extrapolated with the P1 sequence's order gives a second limit; its distance
from the reference is stated as the reference's uncertainty. Pulls: the grab's force (sphere_loads) at
the last time, and its Richardson extrapolation.
"""
import pathlib
import sys

import h5py
import numpy as np
from scipy.spatial import cKDTree

GRIPS = ("volume", "nodes")


def load(out, name):
    with h5py.File(out / f"{name}.h5", "r") as f:
        t = f["/trajectory"]
        time = t["time"][:]
        v = t["surface/vertices"][:].astype(np.float64)
        rest = t["surface/rest_vertices"][:].astype(np.float64)
        loads = t["tools/sphere_loads"][:] if "tools/sphere_loads" in t else None
    return time, v, rest, loads


def inside_mesh(mesh_file, points):
    """Which points lie in a tet of the mesh (barycentric test, 1e-9 slack), by the 24 nearest tet centroids."""
    with h5py.File(mesh_file, "r") as f:
        nodes = f["/tetmesh/nodes"][:]
        tets = f["/tetmesh/tets"][:]
    corners = nodes[tets]                     # T x 4 x 3
    tree = cKDTree(corners.mean(axis=1))
    _, near = tree.query(points, k=24)
    inside = np.zeros(len(points), dtype=bool)
    for j in range(near.shape[1]):
        c = corners[near[:, j]]               # P x 4 x 3
        m = np.stack([c[:, 1] - c[:, 0], c[:, 2] - c[:, 0], c[:, 3] - c[:, 0]], axis=2)
        b = np.linalg.solve(m, (points - c[:, 0])[:, :, None])[:, :, 0]
        inside |= (b.min(axis=1) >= -1e-9) & (b.sum(axis=1) <= 1 + 1e-9)
    return inside


def rms(d):
    return float(np.sqrt((d ** 2).mean()))


def main():
    out = pathlib.Path(sys.argv[1])
    cases = {}
    for path in sorted(out.glob("*.h5")):
        if path.stem.startswith("mesh"):
            continue
        cases[path.stem] = load(out, path.stem)
    ref_time = cases["p1_m0_volume"][0][1:]     # the compared times (1.03, 2.07, 3.10 s)
    picked = {}
    for name, (time, v, _, loads) in cases.items():
        idx = [int(np.argmin(abs(time - t))) for t in ref_time]
        if max(abs(time[idx] - ref_time)) > 1e-6:
            sys.exit(f"nested_convergence.py: {name}: no frames at {ref_time}")
        force = None if loads is None else np.linalg.norm(loads[idx[-1], 0, 1:4])
        picked[name] = (v[idx], force)
    rest = cases["p1_m0_volume"][2]
    inside = inside_mesh(out / "mesh0.h5", rest)
    seconds = {n: (out / f"{n}.time").read_text().split() for n in cases if (out / f"{n}.time").exists()}

    print(f"Compared at t = {', '.join(f'{t:.2f}' for t in ref_time)} s; {inside.sum()} of {len(rest)} surface vertices inside the 6 mm mesh.")
    print()
    print("| grip | t (s) | RMS change 6 mm → 3 mm (mm) | 3 mm → 1.5 mm (mm) | observed order | Richardson: error left at 1.5 mm, RMS (mm) | same, inside the mesh (mm) | pull at 6, 3, 1.5 mm → extrapolated (N) |")
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    reference, orders = {}, {}
    for grip in GRIPS:
        names = [f"p1_m{k}_{grip}" for k in range(3)]
        if not all(n in picked for n in names):
            continue
        u = [picked[n][0] for n in names]
        star = np.empty_like(u[2])
        for f, t in enumerate(ref_time):
            d01 = np.linalg.norm(u[1][f] - u[0][f], axis=1)
            d12 = np.linalg.norm(u[2][f] - u[1][f], axis=1)
            p = np.log2(rms(d01) / rms(d12))
            orders.setdefault(grip, []).append(p)
            star[f] = u[2][f] + (u[2][f] - u[1][f]) / (2 ** p - 1)
            left = np.linalg.norm(star[f] - u[2][f], axis=1)
            pulls = ""
            if f == len(ref_time) - 1:
                fs = [picked[n][1] for n in names]
                pulls = f"{fs[0]:.3f}, {fs[1]:.3f}, {fs[2]:.3f}"
                # Extrapolated only where the changes shrink in one direction.
                if (fs[1] - fs[0]) * (fs[2] - fs[1]) > 0 and abs(fs[2] - fs[1]) < abs(fs[1] - fs[0]):
                    q = np.log2(abs(fs[1] - fs[0]) / abs(fs[2] - fs[1]))
                    pulls += f" → {fs[2] + (fs[2] - fs[1]) / (2 ** q - 1):.3f} (order {q:.2f})"
                else:
                    pulls += " (not monotone: no extrapolation)"
            print(f"| {grip} | {t:.2f} | {rms(d01):.3f} | {rms(d12):.3f} | {p:.2f} | {rms(left):.3f} | {rms(left[inside]):.3f} | {pulls} |")
        reference[grip] = star
    if "volume" not in reference:
        sys.exit("nested_convergence.py: the volume grip's P1 sequence is missing")
    ref = reference["volume"]
    # A second, independent limit: the P2 pair extrapolated with the P1 sequence's observed order (the
    # same singularities, the grip's band and the fixed plane, limit both). Its distance from the
    # reference is the reference's uncertainty.
    if "p2_m0_volume" in picked and "p2_m1_volume" in picked:
        a, b = picked["p2_m0_volume"][0], picked["p2_m1_volume"][0]
        p2star = np.stack([b[f] + (b[f] - a[f]) / (2 ** orders["volume"][f] - 1) for f in range(len(ref_time))])
        reference["p2"] = p2star
        d = np.linalg.norm(p2star - ref, axis=2)
        print()
        print("The P2 pair (6 and 3 mm, volume grip) extrapolated with the same order is "
              + ", ".join(f"{np.sqrt((d[f] ** 2).mean()):.3f}" for f in range(len(ref_time)))
              + f" mm RMS from the reference at the three times (95th percentile at the end {np.percentile(d[-1], 95):.3f} mm, "
              f"largest {d[-1].max():.3f} mm; over the vertices inside the mesh {np.sqrt((d[-1][inside] ** 2).mean()):.3f} mm RMS, "
              f"95th percentile {np.percentile(d[-1][inside], 95):.3f}, largest {d[-1][inside].max():.3f} mm): "
              "the reference's own uncertainty.")
    print()
    print("Against the reference (the volume grip's extrapolated surface), at the last time (t = "
          f"{ref_time[-1]:.2f} s) and the worst of the three:")
    print()
    print("| case | nodes | RMS at the end (mm) | RMS, worst time (mm) | max, any vertex and time (mm) | RMS inside the mesh, worst time (mm) | pull at the end (N) | run (s) | peak memory (MiB) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    labels = {
        "live": "**the live model** (P1, 6 mm, node grip, heart_live's quasi-Newton to 0.05 mm, 1/30 s frames)",
    }
    for grip in GRIPS:
        for k, h in enumerate(("6", "3", "1.5")):
            labels[f"p1_m{k}_{grip}"] = f"P1, {h} mm, {grip} grip"
        for k, h in enumerate(("6", "3")):
            labels[f"p2_m{k}_{grip}"] = f"P2, {h} mm, {grip} grip"
    labels["star_p2"] = "P2 pair extrapolated, volume grip"
    for grip in GRIPS:
        if grip != "volume" and grip in reference:
            labels[f"star_{grip}"] = f"P1 extrapolated, {grip} grip"
    nodes = {}
    for name in cases:
        with h5py.File(out / f"{name}.h5", "r") as f:
            m = f["/trajectory/metrics"]
            nodes[name] = int(m["nodes"][-1]) if "nodes" in m else 0
    for name, label in labels.items():
        if name.startswith("star_"):
            if name[5:] not in reference:
                continue
            v, force, n = reference[name[5:]], None, 0
        elif name in picked:
            v, force = picked[name]
            n = nodes[name]
        else:
            continue
        d = np.linalg.norm(v - ref, axis=2)           # times x vertices
        r = np.sqrt((d ** 2).mean(axis=1))
        r_in = np.sqrt((d[:, inside] ** 2).mean(axis=1))
        s = seconds.get(name, ["-", "-"])
        mem = f"{int(s[0]) / 1024:.0f}" if s[0] != "-" else "-"
        print(f"| {label} | {f'{n:,}' if n else '-'} | {r[-1]:.3f} | {r.max():.3f} | {d.max():.3f} | {r_in.max():.3f} | "
              f"{'-' if force is None else f'{force:.3f}'} | {s[1]} | {mem} |")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Comparison table of simulated models (the FEM paper's comparison): one row per trajectory.

    compare-table.py -o comparison.md TRAJ.h5 [TRAJ.h5 ...]

For each trajectory (ctsurg-sim output): its model and scenario, the enclosed volume and surface area
at rest and in the last frame (change in %), the largest particle/node displacement over the run and
in the last frame, the largest surface-vertex displacement and the mean surface-vertex displacement
in the last frame. Volume and maximum displacements come
from /trajectory/metrics, the area too (surface_area; summed from the frame's surface triangles when a
trajectory predates that metric).
Writes Markdown atomically (temporary file, then rename). Needs h5py and numpy (Debian python3-h5py).
"""
import argparse
import os
import sys

import h5py
import numpy as np


def area(vertices, faces):
    a = vertices[faces[:, 1]] - vertices[faces[:, 0]]
    b = vertices[faces[:, 2]] - vertices[faces[:, 0]]
    return 0.5 * np.linalg.norm(np.cross(a.astype(np.float64), b.astype(np.float64)), axis=1).sum()


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def row(path):
    with h5py.File(path, "r") as f:
        t = f["/trajectory"]
        s = t["surface"]
        m = t["metrics"]
        topo = s["topology_of_frame"][...]
        rest_faces = s[f"topologies/{int(topo[0])}"][...]
        last_faces = s[f"topologies/{int(topo[-1])}"][...]
        rest = s["rest_vertices"][...]
        last = s["vertices"][-1]
        vol = m["enclosed_volume"][...] if "enclosed_volume" in m else None
        maxd = m["max_displacement"][...] if "max_displacement" in m else None
        smaxd = m["surface_max_displacement"][...] if "surface_max_displacement" in m else None
        if "surface_area" in m:  # ctsurg-sim's own metric (mm²)
            a0, a1 = float(m["surface_area"][0]), float(m["surface_area"][-1])
        else:
            a0, a1 = area(rest, rest_faces), area(last, last_faces)
        return {
            "file": os.path.basename(path),
            "model": text(t.attrs.get("model", "?")),
            "scenario": text(t.attrs.get("scenario", "?")),
            "frames": int(t.attrs.get("frames", len(topo))),
            "v0": vol[0] / 1000 if vol is not None else float("nan"),
            "v1": vol[-1] / 1000 if vol is not None else float("nan"),
            "a0": a0 / 100, "a1": a1 / 100,
            "dmax": float(np.max(maxd)) if maxd is not None else float("nan"),
            "dlast": float(maxd[-1]) if maxd is not None else float("nan"),
            "smax": float(np.max(smaxd)) if smaxd is not None else float("nan"),
            "smean": float(np.linalg.norm((last - rest).astype(np.float64), axis=1).mean())
            if last.shape == rest.shape else float("nan"),
        }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("trajectories", nargs="+")
    a = ap.parse_args()
    rows = []
    for p in a.trajectories:
        try:
            rows.append(row(p))
        except (OSError, KeyError) as e:
            print(f"compare-table: {p}: {e}", file=sys.stderr)
            sys.exit(2)
    pct = lambda x0, x1: 100.0 * (x1 - x0) / x0 if x0 else float("nan")
    lines = [
        "# Model comparison",
        "",
        "Same organ, same tool motion; one row per simulated model (scripts/compare-table.py).",
        "Volume: enclosed by the surface (mL); area: surface area (cm²); displacements in mm "
        "(largest over all particles/nodes during the run and in the last frame; surface vertices over the run; "
        "mean over the surface vertices in the last frame: how far the load spreads).",
        "",
        "| model | scenario | frames | volume rest (mL) | volume last (mL) | Δ volume | area rest (cm²) | area last (cm²) | Δ area | max displacement (mm) | last-frame max (mm) | surface max (mm) | surface mean, last (mm) | trajectory |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['scenario']} | {r['frames']} | {r['v0']:.2f} | {r['v1']:.2f} | {pct(r['v0'], r['v1']):+.2f} % | "
            f"{r['a0']:.2f} | {r['a1']:.2f} | {pct(r['a0'], r['a1']):+.2f} % | {r['dmax']:.2f} | {r['dlast']:.2f} | {r['smax']:.2f} | {r['smean']:.3f} | {r['file']} |")
    tmp = f"{a.output}.tmp{os.getpid()}"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, a.output)


if __name__ == "__main__":
    main()

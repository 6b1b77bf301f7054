#!/usr/bin/env python3
"""Writes the bundled instrument meshes of data_samples/instruments/ (deterministic: the same bytes on
every run; rerun after changing a shape and commit the files).

Each instrument is a closed, outward-wound triangle mesh in millimetres, in its own frame: the point a
scenario's path moves (the working tip) at the origin, the shaft along +z. Every shape is a convex
profile swept along a path with a scale per station, closed by two caps: a sweep is closed and
consistently oriented by construction (ctsurg checks both when it loads one, sim/base/instrument.h).

  probe_rod.stl        a 5 mm rod, 80 mm long, with a rounded tip (binary STL)
  retractor_blade.obj  a 20 mm wide, 1.5 mm thick blade bent through 60 degrees (Wavefront OBJ)
  forceps_jaw.ply      one jaw of a grasping forceps: 4 x 3 mm tapering to 2 x 1.5 mm, 30 mm (ASCII PLY)
  scalpel.stl          a no. 10 scalpel blade: a 0.6 mm thick lens profile, 40 mm, rounded belly (ASCII STL)

  python3 scripts/make_instruments.py [OUTPUT_FOLDER]     (default data_samples/instruments)
"""
import math
import os
import struct
import sys


def sweep(stations, profile):
    """stations: [(point, normal_dir, binormal_dir, sx, sy)], profile: [(u, v)] convex, counter-clockwise.
    Returns (vertices, faces) of the closed tube with fan caps, wound outwards."""
    V, F = [], []
    m = len(profile)
    for p, n, b, sx, sy in stations:
        for u, v in profile:
            V.append(tuple(p[i] + sx * u * n[i] + sy * v * b[i] for i in range(3)))
    for k in range(len(stations) - 1):
        for j in range(m):
            a, c = k * m + j, k * m + (j + 1) % m
            F.append((a, c, c + m))
            F.append((a, c + m, a + m))
    for k, flip in ((0, True), (len(stations) - 1, False)):
        centre = len(V)
        V.append(tuple(stations[k][0]))
        for j in range(m):
            a, c = k * m + j, k * m + (j + 1) % m
            F.append((centre, c, a) if flip else (centre, a, c))
    # Outward winding: positive signed volume.
    vol = 0.0
    for a, b, c in F:
        A, B, C = V[a], V[b], V[c]
        vol += (A[0] * (B[1] * C[2] - B[2] * C[1]) - A[1] * (B[0] * C[2] - B[2] * C[0]) + A[2] * (B[0] * C[1] - B[1] * C[0]))
    if vol < 0:
        F = [(a, c, b) for a, b, c in F]
    return V, F


def circle(n):
    return [(math.cos(2 * math.pi * j / n), math.sin(2 * math.pi * j / n)) for j in range(n)]


def probe_rod():
    r, length, rings = 2.5, 80.0, 8
    st = []
    # The rounded tip: rings of a hemisphere around (0, 0, r) at polar angles from 10 degrees (a small
    # flat cap at the very tip, so no ring has zero size) to 90 degrees.
    for i in range(rings):
        theta = math.radians(10 + 80 * i / (rings - 1))
        st.append(((0.0, 0.0, r - r * math.cos(theta)), (1, 0, 0), (0, 1, 0), r * math.sin(theta), r * math.sin(theta)))
    st.append(((0.0, 0.0, length), (1, 0, 0), (0, 1, 0), r, r))
    return sweep(st, circle(24))


def retractor_blade():
    w, t, straight, radius, angle = 20.0, 1.5, 25.0, 15.0, math.radians(60)
    st = []
    # The working end at the origin: straight along +z, then bent towards -y about the x axis.
    for i in range(6):
        z = straight * i / 5
        st.append(((0.0, 0.0, z), (1, 0, 0), (0, 1, 0), w / 2, t / 2))
    for i in range(1, 13):
        a = angle * i / 12
        p = (0.0, -radius + radius * math.cos(a), straight + radius * math.sin(a))
        b = (0.0, math.cos(a), math.sin(a))  # the thickness direction turns with the bend
        st.append((p, (1, 0, 0), b, w / 2, t / 2))
    return sweep(st, [(-1, -1), (1, -1), (1, 1), (-1, 1)])


def forceps_jaw():
    st = []
    for i in range(11):
        z = 30.0 * i / 10
        s = 1.0 + 1.0 * i / 10  # 2 x 1.5 mm at the tip, 4 x 3 mm at the hinge
        st.append(((0.0, 0.0, z), (1, 0, 0), (0, 1, 0), 1.0 * s, 0.75 * s))
    # A rounded-rectangle profile (8 sides): the jaw's edges are not sharp.
    prof = [(-1, -0.6), (-0.6, -1), (0.6, -1), (1, -0.6), (1, 0.6), (0.6, 1), (-0.6, 1), (-1, 0.6)]
    return sweep(st, prof)


def scalpel():
    st = []
    # Belly: the blade's width grows from a 1 mm point to 9 mm, along 40 mm; lens profile 0.6 mm thick.
    for i in range(16):
        z = 40.0 * i / 15
        wdt = 0.5 + 4.0 * math.sin(min(1.0, z / 18.0) * math.pi / 2)
        st.append(((0.0, 0.0, z), (1, 0, 0), (0, 1, 0), wdt, 0.3))
    prof = [(math.cos(a), 0.9 * math.sin(a)) for a in (2 * math.pi * j / 12 for j in range(12))]
    return sweep(st, prof)


def write_stl_binary(path, V, F, name):
    with open(path, "wb") as f:
        f.write(name.encode().ljust(80, b" ")[:80])
        f.write(struct.pack("<I", len(F)))
        for a, b, c in F:
            A, B, C = V[a], V[b], V[c]
            n = normal(A, B, C)
            f.write(struct.pack("<12fH", *n, *A, *B, *C, 0))


def write_stl_ascii(path, V, F, name):
    with open(path, "w", newline="\n") as f:
        f.write(f"solid {name}\n")
        for a, b, c in F:
            n = normal(V[a], V[b], V[c])
            f.write(f"  facet normal {n[0]:.6e} {n[1]:.6e} {n[2]:.6e}\n    outer loop\n")
            for p in (V[a], V[b], V[c]):
                f.write(f"      vertex {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
            f.write("    endloop\n  endfacet\n")
        f.write(f"endsolid {name}\n")


def write_obj(path, V, F, name):
    with open(path, "w", newline="\n") as f:
        f.write(f"# ctsurg instrument: {name} (mm, tip at the origin); scripts/make_instruments.py\no {name}\n")
        for p in V:
            f.write(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
        for a, b, c in F:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")


def write_ply(path, V, F, name):
    with open(path, "w", newline="\n") as f:
        f.write(f"ply\nformat ascii 1.0\ncomment ctsurg instrument: {name} (mm, tip at the origin)\n")
        f.write(f"element vertex {len(V)}\nproperty float x\nproperty float y\nproperty float z\n")
        f.write(f"element face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n")
        for p in V:
            f.write(f"{p[0]:.6f} {p[1]:.6f} {p[2]:.6f}\n")
        for a, b, c in F:
            f.write(f"3 {a} {b} {c}\n")


def normal(A, B, C):
    u = [B[i] - A[i] for i in range(3)]
    v = [C[i] - A[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    s = math.sqrt(sum(x * x for x in n)) or 1.0
    return [x / s for x in n]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data_samples", "instruments")
    os.makedirs(out, exist_ok=True)
    write_stl_binary(os.path.join(out, "probe_rod.stl"), *probe_rod(), "probe_rod")
    write_obj(os.path.join(out, "retractor_blade.obj"), *retractor_blade(), "retractor_blade")
    write_ply(os.path.join(out, "forceps_jaw.ply"), *forceps_jaw(), "forceps_jaw")
    write_stl_ascii(os.path.join(out, "scalpel.stl"), *scalpel(), "scalpel")


if __name__ == "__main__":
    main()

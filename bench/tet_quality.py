#!/usr/bin/env python3
"""Quality of a TetGen mesh (NAME.node + NAME.ele), with the measures of
mesh/include/ctsurg/mesh/tet_mesh_quality.h, for the peer comparison in bench/run.sh.

  bench/tet_quality.py NAME      prints: nodes tets min_dihedral max_dihedral slivers(<10 deg)
                                         mean_radius_edge max_radius_edge volume_mm3 inverted
"""
import sys

import numpy as np


def read_table(path, cols):
    with open(path) as f:
        lines = [l.split('#')[0].split() for l in f]
    lines = [l for l in lines if l]
    n = int(lines[0][0])
    return np.array([[float(x) for x in l[1:1 + cols]] for l in lines[1:1 + n]]), int(lines[1][0])


def main():
    name = sys.argv[1]
    nodes, _ = read_table(name + '.node', 3)
    ele, first = read_table(name + '.ele', 4)
    tets = ele.astype(np.int64) - first
    p = nodes[tets]  # (T, 4, 3)
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    vol = np.einsum('ij,ij->i', a, np.cross(b, c)) / 6.0
    # TetGen's .ele order is negatively oriented in our convention for about half the writers; take
    # |volume| for the quality measures and report the sign separately.
    inverted = int(np.sum(vol <= 0)) if np.sum(vol > 0) >= np.sum(vol < 0) else int(np.sum(vol >= 0))
    # Outward face normals (face f opposite vertex f).
    normals = []
    for f in range(4):
        i, j, k = [(f + s) % 4 for s in (1, 2, 3)]
        n = np.cross(p[:, j] - p[:, i], p[:, k] - p[:, i])
        flip = np.einsum('ij,ij->i', n, p[:, f] - p[:, i]) > 0
        n[flip] *= -1
        normals.append(n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300))
    angles = []
    for e0, e1 in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]:
        c0, c1 = [v for v in range(4) if v not in (e0, e1)]
        cosang = np.clip(np.einsum('ij,ij->i', normals[c0], normals[c1]), -1.0, 1.0)
        angles.append(180.0 - np.degrees(np.arccos(cosang)))
    angles = np.stack(angles, axis=1)
    # Circumradius / shortest edge.
    det = 2.0 * np.einsum('ij,ij->i', a, np.cross(b, c))
    num = (np.sum(a * a, 1)[:, None] * np.cross(b, c) + np.sum(b * b, 1)[:, None] * np.cross(c, a) +
           np.sum(c * c, 1)[:, None] * np.cross(a, b))
    r = np.linalg.norm(num, axis=1) / np.abs(det)
    edges = [p[:, j] - p[:, i] for i, j in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]]
    lmin = np.min(np.stack([np.linalg.norm(e, axis=1) for e in edges], axis=1), axis=1)
    re = r / lmin
    print(len(nodes), len(tets), f'{angles.min():.2f}', f'{angles.max():.2f}', int(np.sum(angles.min(axis=1) < 10.0)),
          f'{re.mean():.3f}', f'{re.max():.3f}', f'{np.abs(vol).sum():.1f}', inverted)


if __name__ == '__main__':
    main()

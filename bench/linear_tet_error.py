#!/usr/bin/env python3
"""What sets the live heart's linear tets' error: volumetric locking, or too few cells to bend?

    linear_tet_error.py MESH0 MESH1 MESH2 [--nu 0.45] [--kinds p1,anp,anp_k,fs]     (about 20 min on 2 cores)

MESH0..2: the live mesh and its nested refinements (ctsurg-tetmesh --refine 1 and 2, as
bench/nested_convergence.sh makes them: the refinements keep the coarse mesh's nodes first, checked).
Linear elasticity (small strain, E 30 kPa, the myocardium preset's nu unless --nu) with the live drag's
boundary conditions: the base fixed (nodes at z >= 85 % of the nodes' bounds) and the 8 mm grab at the
apex holding the material inside its sphere towards the drag's end offset (8.704, -21.76, -8.704) mm by
a penalty k w |u - g|^2 over the volume (k = 1000 E / r^2, w a smoothstep band 2 mm wide at the radius,
lumped at the nodes by a one-point rule a tet: it converges as the mesh is refined). Linear elasticity
stands in for the Neo-Hookean drag because the question is the elements', not the law's; its P1 errors
are of the same size (3.0 mm here at 6 mm against the nonlinear 2.5, docs/accuracy.md).

Linear-tet formulations on each mesh (--kinds):
  p1     standard constant-strain tets;
  anp    averaged nodal pressure on lambda's term (Bonet and Burton 1998, "A simple average nodal pressure
         tetrahedral element for incompressible and nearly incompressible dynamic explicit applications"):
         lambda/2 (div u)^2 integrated at the nodes, the divergence averaged over each node's tets by
         volume; mu (eps : eps) stays per tet. Locking-free as nu -> 0.5;
  anp_k  the same on the whole volumetric term, kappa = lambda + 2 mu / 3, mu's deviatoric part per tet;
  fs     face-based strain smoothing (FS-FEM-T4: Nguyen-Thoi, Liu, Lam and Zhang 2009, "A face-based
         smoothed finite element method (FS-FEM) for 3D linear and geometrically non-linear solid mechanics
         problems using 4-node tetrahedral elements"): the strain averaged by volume over the two tets of
         each face, integrated over a quarter of each; softer in bending than p1.
All four are the same continuum energy (a uniform strain gives each the same energy, checked on the
mesh), so they converge to one limit. The reference is the first kind's (p1) Richardson extrapolation
with its observed order; each case's error is its RMS distance from it over the 6 mm mesh's boundary
nodes, in all and in three zones (near the grab, near the fixed plane, elsewhere). Also printed: how
many of the 6 mm mesh's nodes lie 0, 1, 2, ... edges from its boundary (a wall's thickness in cells).

Solves: sparse direct (scipy's SuperLU) below 200k unknowns, Jacobi-preconditioned conjugate gradients
above (relative residual 1e-9). Needs numpy, scipy and h5py (Debian: python3-scipy python3-h5py).
"""
import argparse
import sys
import time

import h5py
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

E = 30e3  # Pa (linear: the displacements do not depend on its value)
RADIUS = 8.0
BAND = 2.0
OFFSET = np.array([8.704, -21.76, -8.704])


def read_mesh(path):
    with h5py.File(path, "r") as f:
        nodes = f["/tetmesh/nodes"][:].astype(np.float64)
        tets = f["/tetmesh/tets"][:].astype(np.int64)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or tets.ndim != 2 or tets.shape[1] != 4:
        sys.exit(f"linear_tet_error.py: {path}: /tetmesh/nodes must be N x 3 and /tetmesh/tets E x 4")
    if tets.min() < 0 or tets.max() >= len(nodes):
        sys.exit(f"linear_tet_error.py: {path}: /tetmesh/tets: an index outside 0..{len(nodes) - 1}")
    return nodes, tets


def gradients(nodes, tets):
    """Shape-function gradients (E x 4 x 3, 1/mm) and volumes (E, mm^3)."""
    x = nodes[tets]
    dm = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]], axis=2)  # columns
    vol = np.linalg.det(dm) / 6.0
    if (vol <= 0).any():
        sys.exit(f"linear_tet_error.py: {int((vol <= 0).sum())} tets with non-positive volume")
    inv = np.linalg.inv(dm)                     # rows: grad N1..N3
    g = np.empty((len(tets), 4, 3))
    g[:, 1:] = inv
    g[:, 0] = -inv.sum(axis=1)
    return g, vol


def boundary_nodes(tets, n):
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    key = np.sort(faces, axis=1)
    uniq, count = np.unique(key, axis=0, return_counts=True)
    mask = np.zeros(n, dtype=bool)
    mask[uniq[count == 1].ravel()] = True
    return mask


def elastic(idx, g, vol, mu, lam, n, chunk=50_000):
    """Sum over domains of vol (B u)^T C (B u): idx (D x m) the domains' node slots, g (D x m x 3) their
    gradient weights (slots may repeat a node), lam the coefficient of (div u)^2; sparse 3n x 3n."""
    m = idx.shape[1]
    eye = np.eye(3)
    k = sp.csr_matrix((3 * n, 3 * n))
    for lo in range(0, len(idx), chunk):
        ix, gx, vx = idx[lo:lo + chunk], g[lo:lo + chunk], vol[lo:lo + chunk]
        d = len(ix)
        dofs = (3 * ix[:, :, None] + np.arange(3)).reshape(d, 3 * m)
        gg = np.einsum("eak,ebk->eab", gx, gx)
        blocks = mu * gg[:, :, None, :, None] * eye[None, None, :, None, :]
        blocks = blocks + mu * np.einsum("ebi,eaj->eaibj", gx, gx)
        if lam != 0:
            div = gx.reshape(d, 3 * m)
            blocks = blocks + lam * np.einsum("ei,ej->eij", div, div).reshape(d, m, 3, m, 3)
        vals = (blocks.reshape(d, 9 * m * m) * vx[:, None]).ravel()
        rows = np.repeat(dofs, 3 * m, axis=1).ravel()
        cols = np.tile(dofs, (1, 3 * m)).ravel()
        k = k + sp.csr_matrix((vals, (rows, cols)), shape=(3 * n, 3 * n))
    return k


def face_domains(tets, g, vol):
    """Face-based smoothing domains (FS-FEM-T4): one per face, the two tets' slots with their
    gradients weighted by volume, and a quarter of each tet's volume."""
    e = len(tets)
    faces = np.sort(np.concatenate([np.delete(tets, i, axis=1) for i in range(4)]), axis=1)
    owner = np.tile(np.arange(e), 4)
    _, inverse = np.unique(faces, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    starts = np.flatnonzero(np.r_[True, np.diff(inverse[order]) != 0])
    count = np.diff(np.r_[starts, len(order)])
    first = owner[order[starts]]
    second = np.where(count == 2, owner[order[np.minimum(starts + 1, len(order) - 1)]], -1)
    two = second >= 0
    v1 = vol[first]
    v2 = np.where(two, vol[np.maximum(second, 0)], 0.0)
    total = v1 + v2
    idx = np.concatenate([tets[first], np.where(two[:, None], tets[np.maximum(second, 0)], tets[first])], axis=1)
    w1 = (v1 / total)[:, None, None]
    w2 = (v2 / total)[:, None, None]
    gd = np.concatenate([w1 * g[first], w2 * g[np.maximum(second, 0)]], axis=1)
    return idx, gd, total / 4.0


def stiffness(nodes, tets, mu, lam, kind):
    n = len(nodes)
    g, vol = gradients(nodes, tets)
    if kind == "fs":
        idx, gd, vd = face_domains(tets, g, vol)
        return elastic(idx, gd, vd, mu, lam, n).tocsr(), vol
    vol_coeff = {"p1": lam, "anp": 0.0, "anp_k": -2.0 * mu / 3.0}[kind]
    k = elastic(tets, g, vol, mu, vol_coeff, n)
    if kind != "p1":
        coeff = lam if kind == "anp" else lam + 2.0 * mu / 3.0
        dofs = (3 * tets[:, :, None] + np.arange(3)).reshape(len(tets), 12)
        div = g.reshape(len(tets), 12)
        nodal_volume = np.bincount(tets.ravel(), weights=np.repeat(vol / 4.0, 4), minlength=n)
        # theta_a = sum_{e at a} (V_e / 4) div_e u / V_a: D is n x 3n
        d_rows = np.repeat(tets, 12, axis=1).ravel()
        d_cols = np.tile(dofs, (1, 4)).ravel()
        d_vals = (np.repeat((vol / 4.0)[:, None] / nodal_volume[tets], 12, axis=1) * np.tile(div, (1, 4))).ravel()
        d = sp.csr_matrix((d_vals, (d_rows, d_cols)), shape=(n, 3 * n))
        k = k + coeff * (d.T @ sp.diags(nodal_volume) @ d)
    return k.tocsr(), vol


def grip(nodes, tets, vol, centre, k):
    """Lumped penalty diagonal (3n) of the volume grip."""
    c = nodes[tets].mean(axis=1)
    r = np.linalg.norm(c - centre, axis=1)
    s = np.clip((RADIUS + BAND / 2 - r) / BAND, 0.0, 1.0)
    w = s * s * (3 - 2 * s)
    lumped = np.bincount(tets.ravel(), weights=np.repeat(k * w * vol / 4.0, 4), minlength=len(nodes))
    return np.repeat(lumped, 3)


def solve(k, p, fixed, target):
    n3 = k.shape[0]
    free = ~fixed
    a = (k + sp.diags(p))[free][:, free].tocsr()
    b = (p * target)[free]
    t0 = time.time()
    if a.shape[0] < 200_000:
        x = spla.spsolve(a.tocsc(), b)
        how = "direct"
    else:
        inv_diag = 1.0 / a.diagonal()
        count = [0]
        x, info = spla.cg(a, b, tol=1e-9, maxiter=50_000, M=sp.diags(inv_diag),
                          callback=lambda _: count.__setitem__(0, count[0] + 1))
        if info != 0:
            sys.exit(f"linear_tet_error.py: conjugate gradients did not converge ({info})")
        how = f"Jacobi CG {count[0]} iterations, residual {np.linalg.norm(a @ x - b) / np.linalg.norm(b):.1e}"
    u = np.zeros(n3)
    u[free] = x
    return u.reshape(-1, 3), how, time.time() - t0


def layers(tets, n):
    """Each node's distance in edges from the boundary (0 on it)."""
    boundary = boundary_nodes(tets, n)
    e = np.concatenate([tets[:, [i, j]] for i in range(4) for j in range(i + 1, 4)])
    a = sp.csr_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    a = (a + a.T).tocsr()
    depth = np.where(boundary, 0, -1)
    front, k = boundary.copy(), 0
    while (depth < 0).any() and front.any():
        k += 1
        front = ((a @ front.astype(np.float64)) > 0) & (depth < 0)
        depth[front] = k
    return depth


def check_same_energy(nodes, tets, mu, lam, kinds):
    """A uniform strain (and a translation) must give every kind p1's energy (and no force)."""
    a = np.array([[0.01, 0.02, 0.0], [0.0, -0.01, 0.03], [0.005, 0.0, 0.02]])
    u = (nodes @ a.T).ravel()
    shift = np.tile([1.0, 2.0, 3.0], len(nodes))
    ref = None
    for kind in kinds:
        k, _ = stiffness(nodes, tets, mu, lam, kind)
        energy = u @ (k @ u)
        ref = energy if ref is None else ref
        if abs(energy - ref) > 1e-9 * abs(ref) or abs(k @ shift).max() > 1e-9 * abs(k).max() * 10:
            sys.exit(f"linear_tet_error.py: {kind}: a uniform strain's energy {energy!r} differs from {kinds[0]}'s {ref!r}, "
                     "or a translation has forces")


def rms(d):
    return float(np.sqrt((d ** 2).mean()))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs=3)
    ap.add_argument("--nu", type=float, default=0.45)
    ap.add_argument("--kinds", default="p1,anp,anp_k,fs")
    args = ap.parse_args()
    nu = args.nu
    mu = E / (2 * (1 + nu))
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    kinds = args.kinds.split(",")
    meshes = [read_mesh(m) for m in args.meshes]
    n0 = len(meshes[0][0])
    for i in (1, 2):
        if not np.array_equal(meshes[i][0][:n0], meshes[0][0]):
            sys.exit(f"linear_tet_error.py: {args.meshes[i]} does not keep {args.meshes[0]}'s nodes first: not a nested refinement")
    nodes0 = meshes[0][0]
    lo, hi = nodes0.min(0), nodes0.max(0)
    p = lo + np.array([0.75, 0.0, 0.2]) * (hi - lo)
    centre = nodes0[np.argmin(((nodes0 - p) ** 2).sum(1))]
    surface0 = boundary_nodes(meshes[0][1], n0)
    check_same_energy(nodes0, meshes[0][1], mu, lam, kinds)
    # Where the error lies: near the grab (within 2 radii of its centre), near the fixed plane (within
    # 12 mm, two of the live mesh's cells) and elsewhere.
    s_nodes = nodes0[surface0]
    zcut0 = lo[2] + 0.85 * (hi[2] - lo[2])
    near_grab = np.linalg.norm(s_nodes - centre, axis=1) <= 2 * RADIUS
    near_fixed = ~near_grab & (s_nodes[:, 2] >= zcut0 - 12.0)
    zones = {"near the grab": near_grab, "near the fixed plane": near_fixed, "elsewhere": ~near_grab & ~near_fixed}
    u = {kind: [] for kind in kinds}
    print(f"nu {nu}: {', '.join(f'{len(m[0]):,}' for m in meshes)} nodes; grab at {np.round(centre, 2)}", file=sys.stderr)
    for level, (nodes, tets) in enumerate(meshes):
        fixed = np.repeat(nodes[:, 2] >= zcut0, 3)
        for kind in kinds:
            k, vol = stiffness(nodes, tets, mu, lam, kind)
            pen = grip(nodes, tets, vol, centre, 1000 * E / RADIUS ** 2)
            target = np.tile(OFFSET, len(nodes))
            sol, how, sec = solve(k, pen, fixed, target)
            print(f"  level {level} {kind}: {how}, {sec:.1f} s", file=sys.stderr)
            u[kind].append(sol[:n0][surface0])
    ref_kind = kinds[0]
    a, b, c = u[ref_kind]
    d01, d12 = rms(np.linalg.norm(b - a, axis=1)), rms(np.linalg.norm(c - b, axis=1))
    order = np.log2(d01 / d12)
    ref = c + (c - b) / (2 ** order - 1)
    print(f"nu {nu}: {ref_kind} changes {d01:.3f} then {d12:.3f} mm RMS (order {order:.2f}); "
          f"reference = its Richardson extrapolation, estimated {rms(np.linalg.norm(ref - c, axis=1)) / (2 ** order - 1):.3f} mm from the limit")
    print()
    zone_text = ", ".join(f"{name} ({m.sum()})" for name, m in zones.items())
    print(f"| nu | element | 6 mm | 3 mm | 1.5 mm | at 6 mm: {zone_text} |")
    print("|---:|---|---:|---:|---:|---|")
    for kind in kinds:
        errs = [rms(np.linalg.norm(x - ref, axis=1)) for x in u[kind]]
        coarse = np.linalg.norm(u[kind][0] - ref, axis=1)
        by_zone = ", ".join(f"{rms(coarse[m]):.2f}" for m in zones.values())
        print(f"| {nu} | {kind} | " + " | ".join(f"{e:.3f}" for e in errs) + f" | {by_zone} |")
    print()
    print(f"mm RMS from the reference over the 6 mm mesh's {surface0.sum()} boundary nodes; the drag is "
          f"{np.linalg.norm(OFFSET):.1f} mm.")
    for level in (0, 1):
        depth = layers(meshes[level][1], len(meshes[level][0]))
        share = np.bincount(depth[depth >= 0]) / len(depth)
        print(f"{args.meshes[level]}: nodes 0, 1, 2, ... edges from the boundary: "
              + ", ".join(f"{100 * x:.1f} %" for x in share))


if __name__ == "__main__":
    main()

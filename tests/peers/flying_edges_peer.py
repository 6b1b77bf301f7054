#!/usr/bin/python3
"""The peer for ctsurg-surface: VTK's vtkFlyingEdges3D (Schroeder, Maynard & Geveci 2015) on the same
field and isovalue, measured the same way.

  flying_edges_peer.py FIELD.h5 DATASET ISO SURFACE.h5      -> JSON: counts, area, volume of both
  flying_edges_peer.py FIELD.h5 DATASET ISO --time THREADS  -> JSON: median wall time of 15 runs of VTK alone

FIELD.h5 is a ctsurg volume file (DATASET e.g. /hu or /grid/fraction, stored as DATASET/data with
geometry attributes); SURFACE.h5 is what ctsurg-surface wrote for that field and iso. Like
ctsurg-surface, a field that is inside (>= iso) on the lattice border is padded with a one-node
frame of min(field min, iso - 1) so that both surfaces are closed (not in --time mode, which times
the field as it is, as bench/bench_marching_cubes.cpp gives it to ctsurg). VTK works in index space scaled by
the spacing; its points are mapped to LPS mm with the lattice's origin and direction before measuring.
Needs Debian's python3-vtk9, python3-h5py and python3-numpy (run with /usr/bin/python3).
"""
import json
import sys
import time

import h5py
import numpy as np
import vtk
from vtk.util import numpy_support


def read_field(path, dataset):
    with h5py.File(path, "r") as f:
        g = f[dataset]
        data = np.asarray(g["data"], dtype=np.float32)  # (k, j, i)
        spacing = np.asarray(g.attrs["spacing_mm"], dtype=float)
        origin = np.asarray(g.attrs["origin_mm"], dtype=float)
        direction = np.asarray(g.attrs["direction"], dtype=float).reshape(3, 3)
    return data, spacing, origin, direction


def pad_if_open(data, iso, spacing, origin, direction):
    border = np.concatenate([data[[0, -1]].ravel(), data[:, [0, -1]].ravel(), data[:, :, [0, -1]].ravel()])
    if not (border >= iso).any():
        return data, origin
    outside = min(float(data.min()), iso - 1.0)
    padded = np.pad(data, 1, mode="constant", constant_values=outside)
    return padded, origin - direction @ spacing  # node (-1, -1, -1) of the original lattice


def flying_edges(data, iso, spacing):
    image = vtk.vtkImageData()
    image.SetDimensions(data.shape[2], data.shape[1], data.shape[0])
    image.SetSpacing(*spacing)
    image.GetPointData().SetScalars(numpy_support.numpy_to_vtk(data.ravel(), deep=True))
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(image)
    fe.SetValue(0, iso)
    fe.SetComputeNormals(True)
    fe.SetComputeGradients(False)
    fe.SetComputeScalars(False)
    return fe


def measures(points, triangles):
    a, b, c = points[triangles[:, 0]], points[triangles[:, 1]], points[triangles[:, 2]]
    cross = np.cross(b - a, c - a)
    return {
        "vertices": int(len(points)),
        "triangles": int(len(triangles)),
        "area_mm2": float(0.5 * np.linalg.norm(cross, axis=1).sum()),
        "volume_mm3": float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0),
    }


def main(argv):
    field_path, dataset, iso = argv[1], argv[2], float(argv[3])
    data, spacing, origin, direction = read_field(field_path, dataset)
    if argv[4] == "--time":  # the field as it is, as bench_marching_cubes gives it to ctsurg
        vtk.vtkSMPTools.Initialize(int(argv[5]))
        fe = flying_edges(data, iso, spacing)
        times = []
        for _ in range(15):
            fe.Modified()
            t = time.perf_counter()
            fe.Update()
            times.append(time.perf_counter() - t)
        out = fe.GetOutput()
        print(json.dumps({"backend": vtk.vtkSMPTools.GetBackend(), "threads": int(argv[5]), "seconds": float(np.median(times)),
                          "nodes": int(data.size), "triangles": out.GetNumberOfCells()}))
        return 0
    data, origin = pad_if_open(data, iso, spacing, origin, direction)
    fe = flying_edges(data, iso, spacing)
    fe.Update()
    out = fe.GetOutput()
    pts = numpy_support.vtk_to_numpy(out.GetPoints().GetData()).astype(float) @ direction.T + origin
    tris = numpy_support.vtk_to_numpy(out.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    with h5py.File(argv[4], "r") as f:
        ours = measures(np.asarray(f["surface/vertices"], dtype=float), np.asarray(f["surface/triangles"], dtype=np.int64))
    print(json.dumps({"vtk": measures(pts, tris), "ctsurg": ours}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

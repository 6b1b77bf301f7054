// Per-point kernels of a rigid instrument's contact (instrument.h): whether a point of the tissue is
// inside the instrument and where it goes when the tissue is pushed out of it. Written once for the
// CPU and CUDA (CTSURG_HD, no std:: containers).
//
// A point p of the run's frame is taken into the instrument's frame (q = R^T (p - c)), its signed
// distance read from the baked grid (signed_distance_grid.h) by trilinear interpolation, and when
// it is inside (phi < 0) moved along the interpolated gradient by -phi plus a skin; three passes, each
// re-reading the grid, bring a point out even where the gradient bends (at the instrument's edges).
// A point outside the grid's box is outside the instrument (the grid extends past the mesh). A pushed
// point ends within about 0.4 grid spacings of the surface: trilinear interpolation rounds the
// instrument's sharp edges by up to that (tests/sim/base/test_instrument.cpp measures it).
//
// Units: mm.
#pragma once

#include "ctsurg/sim/base/kernels/kernel_support.h"

#include <stdint.h>

namespace ctsurg::sim {

struct InstrumentView {
  const float* phi = nullptr;  // signed distance, mm, x fastest
  int32_t nx = 0, ny = 0, nz = 0;
  double ox = 0, oy = 0, oz = 0;  // the grid's first node, instrument frame, mm
  double spacing = 0;             // mm
  double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // the pose: rotation (row-major, instrument -> run frame)
  double cx = 0, cy = 0, cz = 0;              // and translation (mm, the run's frame)
  double skin = 0;                            // mm a pushed point ends outside the surface
};

// The signed distance at q (instrument frame) and its gradient; false when q is outside the grid.
CTSURG_HD inline bool instrument_distance(const InstrumentView& v, double qx, double qy, double qz, double* phi,
                                          double* gx, double* gy, double* gz) {
  const double fx = (qx - v.ox) / v.spacing, fy = (qy - v.oy) / v.spacing, fz = (qz - v.oz) / v.spacing;
  if (!(fx >= 0 && fy >= 0 && fz >= 0 && fx <= v.nx - 1 && fy <= v.ny - 1 && fz <= v.nz - 1)) return false;
  int32_t i = static_cast<int32_t>(fx), j = static_cast<int32_t>(fy), k = static_cast<int32_t>(fz);
  if (i > v.nx - 2) i = v.nx - 2;
  if (j > v.ny - 2) j = v.ny - 2;
  if (k > v.nz - 2) k = v.nz - 2;
  const double tx = fx - i, ty = fy - j, tz = fz - k;
  const int64_t sx = 1, sy = v.nx, sz = static_cast<int64_t>(v.nx) * v.ny;
  const int64_t n = i + sy * j + sz * k;
  const double c000 = v.phi[n], c100 = v.phi[n + sx], c010 = v.phi[n + sy], c110 = v.phi[n + sx + sy];
  const double c001 = v.phi[n + sz], c101 = v.phi[n + sx + sz], c011 = v.phi[n + sy + sz], c111 = v.phi[n + sx + sy + sz];
  const double c00 = c000 + tx * (c100 - c000), c10 = c010 + tx * (c110 - c010);
  const double c01 = c001 + tx * (c101 - c001), c11 = c011 + tx * (c111 - c011);
  const double c0 = c00 + ty * (c10 - c00), c1 = c01 + ty * (c11 - c01);
  *phi = c0 + tz * (c1 - c0);
  // The trilinear interpolant's derivatives (per cell: continuous inside it, enough for a direction).
  const double dx00 = c100 - c000, dx10 = c110 - c010, dx01 = c101 - c001, dx11 = c111 - c011;
  const double dx0 = dx00 + ty * (dx10 - dx00), dx1 = dx01 + ty * (dx11 - dx01);
  *gx = (dx0 + tz * (dx1 - dx0)) / v.spacing;
  *gy = ((c10 - c00) + tz * ((c11 - c01) - (c10 - c00))) / v.spacing;
  *gz = (c1 - c0) / v.spacing;
  return true;
}

// Moves point p (the run's frame, mm) out of the instrument; returns 1 when it was inside. A point
// where the gradient vanishes (a medial point of the instrument) leaves along the instrument's +z.
CTSURG_HD inline int push_point_out_of_instrument(const InstrumentView& v, double* p) {
  const double px = p[0] - v.cx, py = p[1] - v.cy, pz = p[2] - v.cz;
  double qx = v.r[0] * px + v.r[3] * py + v.r[6] * pz;  // R^T (p - c)
  double qy = v.r[1] * px + v.r[4] * py + v.r[7] * pz;
  double qz = v.r[2] * px + v.r[5] * py + v.r[8] * pz;
  int moved = 0;
  for (int pass = 0; pass < 3; ++pass) {
    double phi = 0, gx = 0, gy = 0, gz = 0;
    if (!instrument_distance(v, qx, qy, qz, &phi, &gx, &gy, &gz) || phi >= 0) break;
    const double g = sqrt(gx * gx + gy * gy + gz * gz);
    if (g > 1e-12) {
      gx /= g, gy /= g, gz /= g;
    } else {
      gx = 0, gy = 0, gz = 1;
    }
    const double step = -phi + v.skin;
    qx += gx * step, qy += gy * step, qz += gz * step;
    moved = 1;
  }
  if (moved) {
    p[0] = v.cx + v.r[0] * qx + v.r[1] * qy + v.r[2] * qz;
    p[1] = v.cy + v.r[3] * qx + v.r[4] * qy + v.r[5] * qz;
    p[2] = v.cz + v.r[6] * qx + v.r[7] * qy + v.r[8] * qz;
  }
  return moved;
}

// The same for a particle's float coordinates.
CTSURG_HD inline int push_out_of_instrument(const InstrumentView& v, Real* x, Real* y, Real* z) {
  double p[3] = {*x, *y, *z};
  if (!push_point_out_of_instrument(v, p)) return 0;
  *x = static_cast<Real>(p[0]), *y = static_cast<Real>(p[1]), *z = static_cast<Real>(p[2]);
  return 1;
}

// An FEM node's displacement u (#N x 3 Real) at rest position rest (#N x 3 double), node i, free
// (inv_mass != 0): moved out of the instrument; returns 1 when it was inside.
CTSURG_HD inline int push_node_out_of_instrument(const InstrumentView& v, Real* u, const double* rest, const Real* inv_mass,
                                                 int32_t i) {
  if (inv_mass[i] == Real(0)) return 0;
  double p[3] = {rest[3 * i] + u[3 * i], rest[3 * i + 1] + u[3 * i + 1], rest[3 * i + 2] + u[3 * i + 2]};
  if (!push_point_out_of_instrument(v, p)) return 0;
  for (int c = 0; c < 3; ++c) u[3 * i + c] = static_cast<Real>(p[c] - rest[3 * i + c]);
  return 1;
}

// The signed distance of a point of the run's frame from the instrument's surface (mm; a large
// positive value outside the grid): for tests and penetration measures.
CTSURG_HD inline double instrument_signed_distance(const InstrumentView& v, double x, double y, double z) {
  const double px = x - v.cx, py = y - v.cy, pz = z - v.cz;
  const double qx = v.r[0] * px + v.r[3] * py + v.r[6] * pz;
  const double qy = v.r[1] * px + v.r[4] * py + v.r[7] * pz;
  const double qz = v.r[2] * px + v.r[5] * py + v.r[8] * pz;
  double phi = 0, gx = 0, gy = 0, gz = 0;
  return instrument_distance(v, qx, qy, qz, &phi, &gx, &gy, &gz) ? phi : 1e30;
}

}  // namespace ctsurg::sim

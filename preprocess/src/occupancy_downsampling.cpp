#include "ctsurg/preprocess/occupancy_downsampling.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"
#include "ctsurg/core/progress_bar.h"
#include "ctsurg/preprocess/tissue_selection.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <sstream>

namespace ctsurg {

namespace {

// Sparse overlap of the voxels [v0, v1] of one axis with the cells of that axis: for every voxel,
// the cells it overlaps and the overlap length divided by the cell edge.
struct AxisOverlap {
  int64_t v0 = 0;
  std::vector<int64_t> begin;  // per voxel (offset v - v0), CSR row start into cell/weight
  std::vector<int64_t> cell;
  std::vector<double> weight;
};

// Voxel v spans [(v - 1/2) s, (v + 1/2) s] along the axis; cell c spans [s0 + c h, s0 + (c + 1) h].
AxisOverlap axis_overlap(int64_t v0, int64_t v1, double s, double s0, double h, int64_t cells) {
  AxisOverlap o;
  o.v0 = v0;
  o.begin.push_back(0);
  for (int64_t v = v0; v <= v1; ++v) {
    const double lo = (double(v) - 0.5) * s, hi = (double(v) + 0.5) * s;
    const int64_t c0 = std::max<int64_t>(0, static_cast<int64_t>(std::floor((lo - s0) / h)));
    const int64_t c1 = std::min<int64_t>(cells - 1, static_cast<int64_t>(std::floor((hi - s0) / h)));
    for (int64_t c = c0; c <= c1; ++c) {
      const double overlap = std::min(hi, s0 + double(c + 1) * h) - std::max(lo, s0 + double(c) * h);
      if (overlap > 0.0) {
        o.cell.push_back(c);
        o.weight.push_back(overlap / h);
      }
    }
    o.begin.push_back(static_cast<int64_t>(o.cell.size()));
  }
  return o;
}

std::string dims_text(const std::array<int64_t, 3>& d) {
  return std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2]);
}

}  // namespace

IndexBox label_bounding_box(const Volume<uint16_t>& mask, uint16_t label) {
  IndexBox box;
  const auto& d = mask.geometry.dims;
  box.lo = {d[0], d[1], d[2]};
  box.hi = {-1, -1, -1};
  size_t n = 0;
  for (int64_t k = 0; k < d[2]; ++k)
    for (int64_t j = 0; j < d[1]; ++j)
      for (int64_t i = 0; i < d[0]; ++i, ++n) {
        const uint16_t v = mask.voxels[n];
        if (label == 0 ? v == 0 : v != label) continue;  // label 0: any non-zero voxel
        const int64_t ijk[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          box.lo[size_t(a)] = std::min(box.lo[size_t(a)], ijk[a]);
          box.hi[size_t(a)] = std::max(box.hi[size_t(a)], ijk[a]);
        }
      }
  return box;
}

IndexBox mask_bounding_box(const Volume<uint16_t>& mask) { return label_bounding_box(mask, 0); }

double occupancy_cell_size(const ImageGeometry& ct, const IndexBox& box, const OccupancyDownsamplingOptions& options) {
  const bool by_size = options.cell_mm != 0.0, by_dim = options.max_dim != 0;
  if (by_size && by_dim) throw InputError("--voxel-mm", "", "give either --voxel-mm or --max-dim, not both");
  if (!by_size && !by_dim) throw InputError("--voxel-mm", "", "give the cell size (--voxel-mm) or --max-dim");
  double h = options.cell_mm;
  if (by_size) {
    if (!std::isfinite(h) || h <= 0.0) {
      std::ostringstream s;
      s << "cell size must be a positive number of mm, got " << h;
      throw InputError("--voxel-mm", "", s.str());
    }
  } else {
    if (options.max_dim < 1) {
      throw InputError("--max-dim", "", "must be a positive number of cells, got " + std::to_string(options.max_dim));
    }
    if (box.empty()) throw InputError("mask", "", "the tissue mask is empty");
    double longest = 0.0;
    for (int a = 0; a < 3; ++a)
      longest = std::max(longest, double(box.hi[size_t(a)] - box.lo[size_t(a)] + 1) * ct.spacing[a]);
    h = longest / double(options.max_dim);
  }
  if (h < ct.spacing.minCoeff()) {
    spdlog::warn("cell size {:.4g} mm is smaller than the CT voxel spacing ({:.4g} mm at the finest): the grid adds no detail",
                 h, ct.spacing.minCoeff());
  }
  return h;
}

ImageGeometry occupancy_cell_lattice(const ImageGeometry& ct, const IndexBox& box, double cell_mm,
                                     const std::string& option) {
  if (box.empty()) throw InputError("mask", "", "the tissue mask is empty");
  ImageGeometry cells;
  cells.direction = ct.direction;
  cells.spacing = Eigen::Vector3d::Constant(cell_mm);
  Eigen::Vector3d first_centre;  // along each CT index axis, mm from the CT origin
  double count = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double s = ct.spacing[a];
    const double length = double(box.hi[size_t(a)] - box.lo[size_t(a)] + 1) * s;
    const double centre = 0.5 * double(box.lo[size_t(a)] + box.hi[size_t(a)]) * s;
    const double inner = std::max(1.0, std::ceil(length / cell_mm - 1e-9));
    const double n = inner + 2.0;  // one empty margin cell on each side
    count *= n;
    if (n > 1e9 || count > 1e15) {
      std::ostringstream m;
      m << "a cell size of " << cell_mm << " mm over the tissue's " << length << " mm gives " << n
        << " cells along axis " << a << " (at least " << count << " cells in all); the grid would be absurdly large";
      throw InputError(option, "grid", m.str());
    }
    cells.dims[size_t(a)] = static_cast<int64_t>(n);
    first_centre[a] = centre - 0.5 * n * cell_mm + 0.5 * cell_mm;
  }
  cells.origin = ct.origin + ct.direction * first_centre;
  // fraction (float) + occupancy + label + two double accumulators per cell.
  check_allocation(static_cast<uint64_t>(cells.voxel_count()), 4 + 1 + 2 + 8 + 8, option,
                   "grid of " + dims_text(cells.dims) + " cells");
  return cells;
}

Volume<double> tissue_volume_fraction(const Volume<uint16_t>& mask, const ImageGeometry& cells, uint16_t label) {
  const ImageGeometry& ct = mask.geometry;
  if ((cells.direction - ct.direction).cwiseAbs().maxCoeff() > 1e-9) {
    throw RuntimeError("tissue_volume_fraction: the cell lattice must share the CT's direction matrix");
  }
  Volume<double> out(cells, 0.0);
  const IndexBox box = label == 0 ? mask_bounding_box(mask) : label_bounding_box(mask, label);
  if (box.empty()) return out;
  const double h = cells.spacing[0];
  const Eigen::Vector3d first = ct.world_to_index(cells.origin);  // CT index of cell (0,0,0)'s centre
  AxisOverlap w[3];
  for (int a = 0; a < 3; ++a) {
    const double s0 = first[a] * ct.spacing[a] - 0.5 * h;  // lower edge of cell 0, mm from the CT origin
    w[a] = axis_overlap(box.lo[size_t(a)], box.hi[size_t(a)], ct.spacing[a], s0, h, cells.dims[size_t(a)]);
  }
  const int64_t nxr = box.hi[0] - box.lo[0] + 1, nyr = box.hi[1] - box.lo[1] + 1, nzr = box.hi[2] - box.lo[2] + 1;
  const int64_t ncx = cells.dims[0], ncy = cells.dims[1];
  check_allocation(static_cast<uint64_t>(ncx * nyr * nzr + ncx * ncy * nzr), sizeof(double), "mask",
                   "occupancy downsampling buffers");
  auto inside = [&](uint16_t v) { return label == 0 ? v != 0 : v == label; };

  // Pass x: A(cx, j, k) = sum_i wx(cx, i) [voxel (i, j, k) is tissue]. Rows are independent.
  std::vector<double> A(static_cast<size_t>(ncx * nyr * nzr), 0.0);
#pragma omp parallel for schedule(static)
  for (int64_t kr = 0; kr < nzr; ++kr) {
    for (int64_t jr = 0; jr < nyr; ++jr) {
      double* row = A.data() + ncx * (jr + nyr * kr);
      const uint16_t* src = &mask(box.lo[0], box.lo[1] + jr, box.lo[2] + kr);
      for (int64_t ir = 0; ir < nxr; ++ir) {
        if (!inside(src[ir])) continue;
        for (int64_t e = w[0].begin[size_t(ir)]; e < w[0].begin[size_t(ir + 1)]; ++e) row[w[0].cell[size_t(e)]] += w[0].weight[size_t(e)];
      }
    }
  }
  // Pass y: B(cx, cy, k) = sum_j wy(cy, j) A(cx, j, k). Slices are independent.
  std::vector<double> B(static_cast<size_t>(ncx * ncy * nzr), 0.0);
#pragma omp parallel for schedule(static)
  for (int64_t kr = 0; kr < nzr; ++kr) {
    for (int64_t jr = 0; jr < nyr; ++jr) {
      const double* a = A.data() + ncx * (jr + nyr * kr);
      for (int64_t e = w[1].begin[size_t(jr)]; e < w[1].begin[size_t(jr + 1)]; ++e) {
        double* b = B.data() + ncx * (w[1].cell[size_t(e)] + ncy * kr);
        const double wy = w[1].weight[size_t(e)];
        for (int64_t cx = 0; cx < ncx; ++cx) b[cx] += wy * a[cx];
      }
    }
  }
  // Pass z: out(cx, cy, cz) = sum_k wz(cz, k) B(cx, cy, k), in a fixed order (deterministic).
  const int64_t plane = ncx * ncy;
  for (int64_t kr = 0; kr < nzr; ++kr) {
    const double* b = B.data() + plane * kr;
    for (int64_t e = w[2].begin[size_t(kr)]; e < w[2].begin[size_t(kr + 1)]; ++e) {
      double* o = out.voxels.data() + plane * w[2].cell[size_t(e)];
      const double wz = w[2].weight[size_t(e)];
      for (int64_t n = 0; n < plane; ++n) o[n] += wz * b[n];
    }
  }
  // Voxel boxes (in index space) scaled to CT spacing vs cubic cells: the weights are lengths over h,
  // so out is already the fraction of the cell's volume.
  for (auto& f : out.voxels) f = std::clamp(f, 0.0, 1.0);
  return out;
}

int64_t drop_unconnected_particles(Volume<uint8_t>& occupancy, bool keep_largest_only, int64_t min_cells) {
  const auto& d = occupancy.geometry.dims;
  const int64_t n_cells = occupancy.geometry.voxel_count();
  std::vector<int32_t> component(static_cast<size_t>(n_cells), -1);
  std::vector<int64_t> sizes;
  // The 18 neighbours: offsets with one or two non-zero components.
  std::vector<std::array<int, 3>> offsets;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nonzero = (dx != 0) + (dy != 0) + (dz != 0);
        if (nonzero == 1 || nonzero == 2) offsets.push_back({dx, dy, dz});
      }
  std::deque<int64_t> queue;
  for (int64_t start = 0; start < n_cells; ++start) {
    if (!occupancy.voxels[size_t(start)] || component[size_t(start)] >= 0) continue;
    const auto id = static_cast<int32_t>(sizes.size());
    int64_t size = 0;
    component[size_t(start)] = id;
    queue.push_back(start);
    while (!queue.empty()) {
      const int64_t n = queue.front();
      queue.pop_front();
      ++size;
      const int64_t i = n % d[0], j = (n / d[0]) % d[1], k = n / (d[0] * d[1]);
      for (const auto& o : offsets) {
        const int64_t ii = i + o[0], jj = j + o[1], kk = k + o[2];
        if (ii < 0 || jj < 0 || kk < 0 || ii >= d[0] || jj >= d[1] || kk >= d[2]) continue;
        const int64_t m = occupancy.geometry.flat_index(ii, jj, kk);
        if (occupancy.voxels[size_t(m)] && component[size_t(m)] < 0) {
          component[size_t(m)] = id;
          queue.push_back(m);
        }
      }
    }
    sizes.push_back(size);
  }
  std::vector<char> keep(sizes.size(), 0);
  size_t largest = 0;
  for (size_t c = 0; c < sizes.size(); ++c) {
    keep[c] = sizes[c] >= 2 && sizes[c] >= min_cells;
    if (sizes[c] > sizes[largest]) largest = c;
  }
  if (keep_largest_only) {
    std::fill(keep.begin(), keep.end(), 0);
    if (!sizes.empty() && sizes[largest] >= 2 && sizes[largest] >= min_cells) keep[largest] = 1;
  }
  int64_t dropped = 0;
  for (int64_t n = 0; n < n_cells; ++n) {
    if (occupancy.voxels[size_t(n)] && !keep[size_t(component[size_t(n)])]) {
      occupancy.voxels[size_t(n)] = 0;
      ++dropped;
    }
  }
  spdlog::debug("particle components (18-connected): {}, dropped {} particles", sizes.size(), dropped);
  return dropped;
}

OccupancyGrid downsample_occupancy(const Volume<uint16_t>& mask, const OccupancyDownsamplingOptions& options,
                                   const std::map<uint16_t, std::string>& label_names) {
  const std::string option = options.cell_mm != 0.0 ? "--voxel-mm" : "--max-dim";
  if (!(options.occupancy_threshold > 0.0 && options.occupancy_threshold <= 1.0)) {
    std::ostringstream s;
    s << "must be in (0, 1], got " << options.occupancy_threshold;
    throw InputError("--occupancy-threshold", "", s.str());
  }
  const IndexBox box = mask_bounding_box(mask);
  if (box.empty()) throw InputError("mask", "", "the tissue mask is empty");
  const double h = occupancy_cell_size(mask.geometry, box, options);
  const ImageGeometry cells = occupancy_cell_lattice(mask.geometry, box, h, option);
  if (!mask.geometry.is_orthonormal(1e-6)) {
    spdlog::warn("the CT lattice is sheared (non-orthonormal direction): cells are parallelepipeds of volume {:.4g} mm^3",
                 cells.voxel_volume_mm3());
  }

  const auto labels = labels_present(mask);
  std::vector<double> total(static_cast<size_t>(cells.voxel_count()), 0.0);
  std::vector<double> best(total.size(), 0.0);
  OccupancyGrid grid;
  grid.label = Volume<uint16_t>(cells, 0);
  {
    ProgressBar bar("occupancy", labels.size());
    for (const auto label : labels) {
      const Volume<double> f = tissue_volume_fraction(mask, cells, labels.size() == 1 ? uint16_t{0} : label);
      for (size_t n = 0; n < total.size(); ++n) {
        total[n] += f.voxels[n];
        if (f.voxels[n] > best[n]) {  // strict: equal volumes keep the lower label id
          best[n] = f.voxels[n];
          grid.label.voxels[n] = label;
        }
      }
      bar.advance();
    }
  }
  grid.fraction = Volume<float>(cells, 0.0f);
  grid.occupancy = Volume<uint8_t>(cells, 0);
  grid.occupancy_threshold = options.occupancy_threshold;
  float max_fraction = 0.0f;
  int64_t above = 0;
  for (size_t n = 0; n < total.size(); ++n) {
    const float f = static_cast<float>(std::clamp(total[n], 0.0, 1.0));
    grid.fraction.voxels[n] = f;
    max_fraction = std::max(max_fraction, f);
    if (double(f) >= options.occupancy_threshold) {
      grid.occupancy.voxels[n] = 1;
      ++above;
    }
  }
  if (above == 0) {
    std::ostringstream s;
    s << "no cell of " << h << " mm reaches the occupancy threshold " << options.occupancy_threshold
      << "; the fullest cell holds " << max_fraction << " (use a lower threshold or larger cells)";
    throw InputError("--occupancy-threshold", "", s.str());
  }
  const int64_t min_cells =
      options.min_component_mm3 > 0.0 ? static_cast<int64_t>(std::ceil(options.min_component_mm3 / cells.voxel_volume_mm3())) : 0;
  const int64_t dropped = drop_unconnected_particles(grid.occupancy, options.keep_largest_only, min_cells);
  if (dropped > 0) spdlog::info("dropped {} particles not connected (18-neighbourhood) to a kept component", dropped);
  if (dropped == above) {
    throw InputError("--occupancy-threshold", "",
                     "every particle is isolated or in a component below --min-component-mm3; no body is left "
                     "(use smaller cells or a lower threshold)");
  }
  grid.mask = mask;
  grid.label_names = label_names;
  return grid;
}

}  // namespace ctsurg

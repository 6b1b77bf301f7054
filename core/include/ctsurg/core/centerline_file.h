// A vessel's centerline: the medial axis of a tubular mask as a graph of polylines (branches) between
// nodes (end points and junctions), each point with its maximal inscribed radius. Written by
// ctsurg-centerline (mesh/centerline_extraction.h), read by the vessel model (sim/vessel/).
//
//   /provenance
//   /centerline/points         (#P, 3) float64  LPS mm, the branches' points one after the other
//   /centerline/radius         (#P)    float64  mm, maximal inscribed radius at each point (> 0)
//   /centerline/branch_offsets (#B + 1) int64   branch b is points [offsets[b], offsets[b+1]), from its
//                                                start node to its end node (>= 2 points); offsets[0] = 0,
//                                                offsets[#B] = #P
//   /centerline/branch_nodes   (#B, 2) int32    (start node, end node) of each branch, into nodes
//   /centerline/nodes          (#N, 3) float64  LPS mm: end points (degree 1) and junctions (degree >= 3);
//                                                a branch's first and last points are its nodes' positions
//   /centerline attributes: points, branches, nodes, frame "LPS", units "mm", label (the mask label,
//                           0 for a binary mask), source_spacing_mm (3), and the extraction's
//                           parameters (parameters, JSON)
//
// plus a VTK polyline sidecar (.vtk, legacy ASCII, POLYDATA with LINES and a "radius" point array) for
// ParaView. See docs/formats.md.
#pragma once

#include "ctsurg/core/atomic_output.h"
#include "ctsurg/core/provenance.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

struct Centerline {
  std::vector<double> points;           // #P x 3, LPS mm, row-major
  std::vector<double> radius;           // #P, mm
  std::vector<int64_t> branch_offsets;  // #B + 1
  std::vector<int32_t> branch_nodes;    // #B x 2
  std::vector<double> nodes;            // #N x 3, LPS mm
  uint16_t label = 0;                   // the mask's label (0: binary mask)
  std::array<double, 3> source_spacing_mm{0, 0, 0};
  std::string parameters;               // JSON of the extraction's parameters

  int64_t point_count() const { return static_cast<int64_t>(radius.size()); }
  int64_t branch_count() const { return branch_offsets.empty() ? 0 : static_cast<int64_t>(branch_offsets.size()) - 1; }
  int64_t node_count() const { return static_cast<int64_t>(nodes.size() / 3); }
};

// Throws InputError(file, "/centerline/...", ...) for no branch, inconsistent sizes, a branch of fewer
// than 2 points, a node index out of range, a node that ends no branch, a branch whose ends are not
// its nodes' positions (within 1e-6 mm), a radius that is not finite and positive, a point or node
// that is not finite, or a source spacing that is negative or not finite (0: unknown).
void validate_centerline(const Centerline& centerline, const std::string& file);
// The VTK sidecar of a centerline file: `h5_path` with suffix .vtk.
std::filesystem::path centerline_vtk_path_for(const std::filesystem::path& h5_path);
// Writes `path` (and its .vtk sidecar) atomically; validates first. The HDF5 file is opened again
// after writing (hdf5_file.h). With a `unit`, both files are added to it and the caller commits it
// with the run's other outputs (a preview image).
void write_centerline_file(const std::filesystem::path& path, const Centerline& centerline, const Provenance& provenance,
                           OutputUnit* unit = nullptr);
// Reads a centerline file; InputError naming the file and object when it is not one or is not valid.
Centerline read_centerline_file(const std::filesystem::path& path);

}  // namespace ctsurg

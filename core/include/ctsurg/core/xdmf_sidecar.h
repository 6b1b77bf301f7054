// XDMF 3 sidecars so ParaView (and VisIt) open ctsurg HDF5 volumes and grids directly.
// Each lattice becomes a 3DCoRectMesh grid; its voxel arrays become node-centred attributes that
// point into the HDF5 file by relative name. XDMF's CoRectMesh has no direction matrix: for an
// oblique or sheared lattice the sidecar places the lattice axis-aligned at its origin and says so in
// an XML comment (the HDF5 file keeps the exact geometry).
#pragma once

#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/volume.h"

#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

struct XdmfArray {
  std::string name;          // attribute name shown in ParaView
  std::string dataset_path;  // HDF5 path, e.g. "/hu/data"
  VoxelType type;
};

struct XdmfLattice {
  std::string name;  // grid name shown in ParaView
  ImageGeometry geometry;
  std::vector<XdmfArray> arrays;
};

// XML text of a sidecar for `h5_file_name` (a name relative to the sidecar's folder).
std::string xdmf_document(const std::string& h5_file_name, const std::vector<XdmfLattice>& lattices);

// Sidecar path for an HDF5 output: same folder and stem, suffix ".xdmf".
std::filesystem::path xdmf_path_for(const std::filesystem::path& h5_path);

}  // namespace ctsurg

#include "ctsurg/core/xdmf_sidecar.h"

#include <cstdio>
#include <sstream>

namespace ctsurg {

namespace {

const char* xdmf_number_type(VoxelType t) {
  switch (t) {
    case VoxelType::UInt8: return "NumberType=\"UChar\" Precision=\"1\"";
    case VoxelType::Int16: return "NumberType=\"Int\" Precision=\"2\"";
    case VoxelType::UInt16: return "NumberType=\"UInt\" Precision=\"2\"";
    case VoxelType::Int32: return "NumberType=\"Int\" Precision=\"4\"";
    case VoxelType::Float32: return "NumberType=\"Float\" Precision=\"4\"";
  }
  return "";
}

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

std::string xdmf_document(const std::string& h5_file_name, const std::vector<XdmfLattice>& lattices) {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<!-- ctsurg sidecar: opens " << h5_file_name << " in ParaView. LPS millimetres. -->\n"
    << "<Xdmf Version=\"3.0\">\n  <Domain>\n";
  for (const auto& lat : lattices) {
    const auto& g = lat.geometry;
    const std::string dims = std::to_string(g.dims[2]) + " " + std::to_string(g.dims[1]) + " " + std::to_string(g.dims[0]);
    if (!g.direction.isIdentity(1e-9)) {
      x << "    <!-- direction matrix is not the identity: shown axis-aligned here; the HDF5 file has the exact "
           "geometry -->\n";
    }
    x << "    <Grid Name=\"" << lat.name << "\" GridType=\"Uniform\">\n"
      << "      <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << dims << "\"/>\n"
      << "      <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
      << "        <DataItem Dimensions=\"3\" Format=\"XML\">" << fmt(g.origin[2]) << " " << fmt(g.origin[1]) << " "
      << fmt(g.origin[0]) << "</DataItem>\n"
      << "        <DataItem Dimensions=\"3\" Format=\"XML\">" << fmt(g.spacing[2]) << " " << fmt(g.spacing[1]) << " "
      << fmt(g.spacing[0]) << "</DataItem>\n"
      << "      </Geometry>\n";
    for (const auto& a : lat.arrays) {
      x << "      <Attribute Name=\"" << a.name << "\" AttributeType=\"Scalar\" Center=\"Node\">\n"
        << "        <DataItem Dimensions=\"" << dims << "\" " << xdmf_number_type(a.type) << " Format=\"HDF\">"
        << h5_file_name << ":" << a.dataset_path << "</DataItem>\n"
        << "      </Attribute>\n";
    }
    x << "    </Grid>\n";
  }
  x << "  </Domain>\n</Xdmf>\n";
  return x.str();
}

std::filesystem::path xdmf_path_for(const std::filesystem::path& h5_path) {
  std::filesystem::path p = h5_path;
  return p.replace_extension(".xdmf");
}

}  // namespace ctsurg

#include "ctsurg/core/volume.h"

namespace ctsurg {

const char* voxel_type_name(VoxelType type) {
  switch (type) {
    case VoxelType::UInt8: return "uint8";
    case VoxelType::Int16: return "int16";
    case VoxelType::UInt16: return "uint16";
    case VoxelType::Int32: return "int32";
    case VoxelType::Float32: return "float32";
  }
  return "unknown";
}

std::size_t voxel_type_size(VoxelType type) {
  switch (type) {
    case VoxelType::UInt8: return 1;
    case VoxelType::Int16:
    case VoxelType::UInt16: return 2;
    case VoxelType::Int32:
    case VoxelType::Float32: return 4;
  }
  return 0;
}

}  // namespace ctsurg

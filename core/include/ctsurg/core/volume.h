// A scalar voxel volume: geometry (image_geometry.h) plus one value per voxel, x fastest.
#pragma once

#include "ctsurg/core/image_geometry.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg {

// Voxel types that ctsurg files store. The HU volume is int16 when every HU value is an integer in
// int16 range (the usual CT case, exact) and float32 otherwise.
enum class VoxelType { UInt8, Int16, UInt16, Int32, Float32 };

const char* voxel_type_name(VoxelType type);
std::size_t voxel_type_size(VoxelType type);

template <class T>
struct Volume {
  ImageGeometry geometry;
  std::vector<T> voxels;  // geometry.voxel_count() values, index i + nx * (j + ny * k)

  Volume() = default;
  explicit Volume(const ImageGeometry& g, T fill = T{}) : geometry(g), voxels(static_cast<std::size_t>(g.voxel_count()), fill) {}

  T& operator()(int64_t i, int64_t j, int64_t k) { return voxels[static_cast<std::size_t>(geometry.flat_index(i, j, k))]; }
  const T& operator()(int64_t i, int64_t j, int64_t k) const {
    return voxels[static_cast<std::size_t>(geometry.flat_index(i, j, k))];
  }
};

}  // namespace ctsurg

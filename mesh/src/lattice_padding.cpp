#include "ctsurg/mesh/lattice_padding.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/memory_guard.h"

#include <algorithm>

namespace ctsurg {

Volume<float> pad_lattice(const Volume<float>& field, float value, int64_t width) {
  if (width < 1) throw InputError("field", "padding", "the padding width must be at least 1 node");
  const ImageGeometry& g = field.geometry;
  ImageGeometry p = g;
  for (int a = 0; a < 3; ++a) p.dims[static_cast<std::size_t>(a)] += 2 * width;
  p.origin = g.index_to_world(Eigen::Vector3d::Constant(-double(width)));
  check_allocation(static_cast<uint64_t>(p.voxel_count()), sizeof(float), "field", "padded lattice");
  Volume<float> out(p, value);
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      const float* src = &field.voxels[static_cast<std::size_t>(g.flat_index(0, j, k))];
      std::copy(src, src + g.dims[0], &out.voxels[static_cast<std::size_t>(p.flat_index(width, j + width, k + width))]);
    }
  return out;
}

}  // namespace ctsurg

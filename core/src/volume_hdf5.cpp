#include "ctsurg/core/volume_hdf5.h"

#include "ctsurg/core/error.h"

#include <array>
#include <cmath>
#include <limits>

namespace ctsurg {

namespace {

// NaN and infinity never enter or leave a stage (finite_values.h); a volume names the voxel.
template <class T>
void require_finite_voxels(const Volume<T>& v, const std::string& file, const std::string& field) {
  if constexpr (std::is_floating_point_v<T>) {
    const auto& d = v.geometry.dims;
    for (std::size_t n = 0; n < v.voxels.size(); ++n) {
      if (std::isfinite(v.voxels[n])) continue;
      const int64_t i = static_cast<int64_t>(n) % d[0], j = static_cast<int64_t>(n) / d[0] % d[1],
                    k = static_cast<int64_t>(n) / (d[0] * d[1]);
      throw InputError(file, field,
                       std::string(std::isnan(v.voxels[n]) ? "NaN" : "an infinite value") + " at voxel (" +
                           std::to_string(i) + ", " + std::to_string(j) + ", " + std::to_string(k) +
                           ") (every value must be finite)");
    }
  }
}

template <class S, class T>
std::vector<S> convert(const std::vector<T>& in) {
  if constexpr (std::is_same_v<S, T>) {
    return in;
  } else {
    std::vector<S> out(in.size());
    for (std::size_t n = 0; n < in.size(); ++n) {
      if constexpr (std::is_integral_v<S> && std::is_floating_point_v<T>) {
        out[n] = static_cast<S>(std::lround(in[n]));
      } else {
        out[n] = static_cast<S>(in[n]);
      }
    }
    return out;
  }
}

template <class S, class T>
void write_as(h5::Group& g, const Volume<T>& v, std::span<const uint64_t> shape) {
  if constexpr (std::is_same_v<S, T>) {
    g.write_dataset<S>("data", v.voxels, shape);
  } else {
    g.write_dataset<S>("data", convert<S>(v.voxels), shape);
  }
}

}  // namespace

template <class T>
void write_volume(h5::Group& parent, const std::string& name, const Volume<T>& volume, const VolumeMeta& meta,
                  VoxelType stored) {
  const ImageGeometry& geo = volume.geometry;
  geo.validate(parent.file() + ": " + parent.path());
  if (volume.voxels.size() != static_cast<std::size_t>(geo.voxel_count())) {
    throw RuntimeError(parent.file() + ": /" + name + ": the volume holds " + std::to_string(volume.voxels.size()) +
                       " voxels, its dims say " + std::to_string(geo.voxel_count()));
  }
  require_finite_voxels(volume, parent.file(), (parent.path() == "/" ? "/" : parent.path() + "/") + name + "/data");
  h5::Group g = parent.create_group(name);
  g.set_attribute("kind", std::string("volume"));
  g.set_attribute("quantity", meta.quantity);
  g.set_attribute("units", meta.units);
  g.set_attribute("frame", std::string("LPS"));
  g.set_attribute("index_order", std::string("data[k][j][i], i fastest"));
  const std::array<int64_t, 3> dims = geo.dims;
  g.set_attribute("dims", std::span<const int64_t>(dims));
  const std::array<double, 3> spacing{geo.spacing[0], geo.spacing[1], geo.spacing[2]};
  const std::array<double, 3> origin{geo.origin[0], geo.origin[1], geo.origin[2]};
  std::array<double, 9> direction{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) direction[static_cast<std::size_t>(3 * r + c)] = geo.direction(r, c);
  g.set_attribute("spacing_mm", std::span<const double>(spacing));
  g.set_attribute("origin_mm", std::span<const double>(origin));
  g.set_attribute("direction", std::span<const double>(direction));
  const std::array<uint64_t, 3> shape{static_cast<uint64_t>(dims[2]), static_cast<uint64_t>(dims[1]),
                                      static_cast<uint64_t>(dims[0])};
  switch (stored) {
    case VoxelType::UInt8: write_as<uint8_t>(g, volume, shape); break;
    case VoxelType::Int16: write_as<int16_t>(g, volume, shape); break;
    case VoxelType::UInt16: write_as<uint16_t>(g, volume, shape); break;
    case VoxelType::Int32: write_as<int32_t>(g, volume, shape); break;
    case VoxelType::Float32: write_as<float>(g, volume, shape); break;
  }
}

ImageGeometry read_volume_geometry(const h5::Group& parent, const std::string& name) {
  const h5::Group g = parent.open_group(name);
  ImageGeometry geo;
  const auto field = [&](const char* attr, std::size_t n) {
    auto v = g.doubles_attribute(attr);
    if (v.size() != n) {
      throw InputError(g.file(), g.path() + "@" + attr,
                       "expected " + std::to_string(n) + " values, found " + std::to_string(v.size()));
    }
    return v;
  };
  const auto dims = field("dims", 3);
  const auto spacing = field("spacing_mm", 3);
  const auto origin = field("origin_mm", 3);
  const auto direction = field("direction", 9);
  for (int a = 0; a < 3; ++a) {
    if (!(dims[a] >= 1 && dims[a] < 1e9)) {
      throw InputError(g.file(), g.path() + "@dims", "dimension " + std::to_string(a) + " out of range");
    }
    geo.dims[a] = static_cast<int64_t>(dims[a]);
    geo.spacing[a] = spacing[a];
    geo.origin[a] = origin[a];
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) geo.direction(r, c) = direction[static_cast<std::size_t>(3 * r + c)];
  geo.validate(g.file() + ": " + g.path());
  const auto shape = g.dataset_shape("data");
  if (shape.size() != 3 || shape[0] != uint64_t(geo.dims[2]) || shape[1] != uint64_t(geo.dims[1]) ||
      shape[2] != uint64_t(geo.dims[0])) {
    throw InputError(g.file(), g.path() + "/data", "dataset shape does not match the dims attribute");
  }
  return geo;
}

VolumeMeta read_volume_meta(const h5::Group& parent, const std::string& name) {
  const h5::Group g = parent.open_group(name);
  return {g.string_attribute("quantity"), g.string_attribute("units")};
}

template <class T>
Volume<T> read_volume(const h5::Group& parent, const std::string& name) {
  Volume<T> v;
  v.geometry = read_volume_geometry(parent, name);
  const h5::Group g = parent.open_group(name);
  v.voxels = g.read_dataset<T>("data");
  require_finite_voxels(v, g.file(), g.path() + "/data");
  return v;
}

#define CTSURG_VOLUME_INSTANTIATE(T)                                                                             \
  template void write_volume<T>(h5::Group&, const std::string&, const Volume<T>&, const VolumeMeta&, VoxelType); \
  template Volume<T> read_volume<T>(const h5::Group&, const std::string&);
CTSURG_VOLUME_INSTANTIATE(uint8_t)
CTSURG_VOLUME_INSTANTIATE(int16_t)
CTSURG_VOLUME_INSTANTIATE(uint16_t)
CTSURG_VOLUME_INSTANTIATE(int32_t)
CTSURG_VOLUME_INSTANTIATE(float)
#undef CTSURG_VOLUME_INSTANTIATE

}  // namespace ctsurg

// PNG encoding of a normal map (OpenCV is confined to normal_map_png.cpp): RGB, 8 or 16 bits per
// channel as the map's `bits`, row 0 at the top (v = 0), no ancillary chunks (no time stamp), so the
// same map gives the same bytes.
#pragma once

#include <cstdint>
#include <vector>

#include "ctsurg/core/surface_mesh_file.h"

namespace ctsurg {

// PNG bytes of `map`. RuntimeError when the encoder fails.
std::vector<uint8_t> encode_normal_map_png(const NormalMapImage& map);
// The map in PNG bytes (3 channels, 8 or 16 bits). InputError(source, "png", ...) when it is not one.
NormalMapImage decode_normal_map_png(const std::vector<uint8_t>& png, const std::string& source);

}  // namespace ctsurg

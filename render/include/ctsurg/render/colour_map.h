// The colour map of heat maps and their colour bars: Google's Turbo (Mikhailov 2019, "Turbo, an
// improved rainbow colormap for visualization"), evaluated with its published polynomial fit, as a
// 256-entry table shared by the shader (a 1D texture) and the colour bar so both show the same colours.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace ctsurg {

// 256 x 3 bytes (RGB): entry i is the colour of the value i / 255 in [0, 1].
const std::vector<uint8_t>& turbo_colour_table();
// The colour of t in [0, 1] (clamped).
std::array<uint8_t, 3> turbo_colour(double t);

}  // namespace ctsurg

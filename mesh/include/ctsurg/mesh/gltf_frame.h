// The frame every glTF file ctsurg writes is in, and the one place that maps LPS millimetres to it.
//
// glTF 2.0 (section 3.4, "Coordinate system and units") is metres, right-handed, +Y up, +Z the
// asset's front (a default viewer looks at it along -Z), +X its left. ctsurg's world is LPS
// millimetres (+x patient left, +y posterior, +z superior). The mapping is
//   p_gltf = kGltfMetresPerMm * R * p_lps,   R = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]
// i.e. x_gltf = x_lps (L stays +X), y_gltf = z_lps (S is up), z_gltf = -y_lps (A faces the viewer).
// det R = +1: a proper rotation, so counter-clockwise winding (outward faces) is kept, normals and
// tangent xyz rotate by R alone and the tangent's handedness w is unchanged. Exporters bake it into
// the vertices (no node transform), so every viewer shows the patient upright, face on, in metres.
#pragma once

#include <array>

namespace ctsurg {

// Metres per millimetre: glTF positions are metres.
inline constexpr double kGltfMetresPerMm = 1e-3;

// R, row-major: row r gives glTF axis r in LPS components.
inline constexpr std::array<std::array<int, 3>, 3> kLpsToGltfRotation{{{1, 0, 0}, {0, 0, 1}, {0, -1, 0}}};

// R d for a direction `d` (3 floats, LPS: a normal or a tangent's xyz); unit length is kept.
constexpr std::array<float, 3> lps_to_gltf_direction(const float* d) {
  std::array<float, 3> out{};
  for (int r = 0; r < 3; ++r) {
    out[r] = static_cast<float>(kLpsToGltfRotation[r][0]) * d[0] + static_cast<float>(kLpsToGltfRotation[r][1]) * d[1] +
             static_cast<float>(kLpsToGltfRotation[r][2]) * d[2];
  }
  return out;
}

// The glTF position, metres, of an LPS position `p` in millimetres (3 floats).
constexpr std::array<float, 3> lps_mm_to_gltf_position(const float* p) {
  const std::array<float, 3> rotated = lps_to_gltf_direction(p);
  return {static_cast<float>(rotated[0] * kGltfMetresPerMm), static_cast<float>(rotated[1] * kGltfMetresPerMm),
          static_cast<float>(rotated[2] * kGltfMetresPerMm)};
}

}  // namespace ctsurg

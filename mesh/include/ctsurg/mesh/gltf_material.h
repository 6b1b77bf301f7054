// The material and the frame note every glTF file ctsurg writes carries (the static surface export,
// mesh/src/surface_export.cpp, and the animated export, render/src/gltf_animation.cpp), kept here
// once so both show the same tissue.
//
// glTF's baseColorFactor is linear (glTF 2.0, section 3.9.2); viewers encode to sRGB on output. The
// colours below are chosen as they should look on screen (sRGB-encoded, as ctsurg-render's tissue
// and wound look) and converted with the sRGB transfer function (IEC 61966-2-1), so a glTF viewer
// shows the tissue as dark as the pictures do instead of washed out.
#pragma once

#include <array>
#include <cmath>

namespace ctsurg {

// The note in asset.extras.ctsurg_frame: how the file's frame relates to LPS (gltf_frame.h).
inline constexpr const char* kGltfFrameNote =
    "metres; glTF +X = patient left, +Y = superior, +Z = anterior (from LPS millimetres: x, z, -y times 0.001)";

// An sRGB-encoded channel (0..1) as a linear value.
inline double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// Tissue: on screen (0.80, 0.42, 0.38), not metallic, roughness 0.55, with the normal map when there is one.
inline constexpr std::array<double, 3> kGltfTissueOnScreen{0.80, 0.42, 0.38};
inline constexpr double kGltfTissueMetallic = 0.0, kGltfTissueRoughness = 0.55;
// The inside of a cut (ctsurg-render's wound colour, surface_renderer.cpp): on screen (0.42, 0.06, 0.08), matte.
inline constexpr std::array<double, 3> kGltfWoundOnScreen{0.42, 0.06, 0.08};
inline constexpr double kGltfWoundRoughness = 0.8;

// Linear RGBA base colour factors of the two materials.
inline std::array<double, 4> gltf_linear_colour(const std::array<double, 3>& on_screen) {
  return {srgb_to_linear(on_screen[0]), srgb_to_linear(on_screen[1]), srgb_to_linear(on_screen[2]), 1.0};
}

}  // namespace ctsurg

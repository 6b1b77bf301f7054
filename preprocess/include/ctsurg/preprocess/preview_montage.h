// A PNG preview for checking a segmentation at a glance: a montage of axial CT slices, greyscale
// in a display window (width / level in HU), with the tissue mask outlined in green and the
// outline of the occupancy-grid particles (the cells that become particles, cut at the slice) in
// magenta. Each tile is labelled with its slice index k and its z in mm (LPS).
// Display is radiological: for an identity (LPS) direction image x = i (patient right on the left
// of the image) and image y = j (anterior at the top); i (j) is mirrored when its direction column
// points to patient right (anterior), as for NIfTI data stored in RAS order. Tiles keep the
// physical aspect ratio.
// OpenCV is confined to preview_montage.cpp.
#pragma once

#include "ctsurg/core/volume.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg {

struct PreviewOptions {
  int slices = 12;                // number of axial slices, evenly over the mask's k extent
  int columns = 4;                // tiles per row
  double window_width = 400.0;    // HU
  double window_level = 40.0;     // HU
  double tile_width_px = 320.0;   // approximate tile width; the scale is the same for every tile
};

// An 8-bit RGB image, rows top to bottom, 3 bytes per pixel.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // width * height * 3
  const uint8_t* pixel(int x, int y) const { return rgb.data() + 3 * (static_cast<size_t>(y) * width + x); }
};

// Colours used for the outlines (RGB).
inline constexpr uint8_t kMaskOutlineRgb[3] = {0, 255, 0};
inline constexpr uint8_t kParticleOutlineRgb[3] = {255, 0, 255};

// The axial slices shown: `count` indices spread evenly over the mask's non-empty k range (fewer
// when the range is shorter), ascending, each the centre of its share of the range.
std::vector<int64_t> preview_slice_indices(const Volume<uint16_t>& mask, int count);

// Renders the montage.
//   hu         CT, HU, on the CT lattice
//   mask       tissue label mask on the same lattice (0 = background)
//   occupancy  particle grid (0/1) on the cell lattice (any lattice; cells are found by position)
// RuntimeError when mask and hu differ in lattice or the mask is empty.
RgbImage render_preview_montage(const Volume<float>& hu, const Volume<uint16_t>& mask,
                                const Volume<uint8_t>& occupancy, const PreviewOptions& options);

// PNG bytes of an image (deterministic: same image, same bytes).
std::string encode_png(const RgbImage& image);

}  // namespace ctsurg

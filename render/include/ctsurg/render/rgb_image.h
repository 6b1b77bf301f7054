// An 8-bit RGB image in memory and its PNG file: what every render ends as. OpenCV (the encoder) is
// confined to rgb_image.cpp and image_composition.cpp.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

struct RgbImage {
  int width = 0, height = 0;  // pixels
  std::vector<uint8_t> rgb;   // height x width x 3, row-major, row 0 at the top of the picture

  RgbImage() = default;
  RgbImage(int w, int h, uint8_t grey = 0)
      : width(w), height(h), rgb(3 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h), grey) {}
  bool empty() const { return rgb.empty(); }
  uint8_t* pixel(int x, int y) { return rgb.data() + 3 * (static_cast<std::size_t>(y) * width + x); }
  const uint8_t* pixel(int x, int y) const { return rgb.data() + 3 * (static_cast<std::size_t>(y) * width + x); }
};

// PNG bytes of `image` (8-bit RGB, no ancillary chunks such as a time stamp: the same pixels give
// the same bytes). RuntimeError when the encoder fails or the image is empty.
std::vector<uint8_t> encode_png(const RgbImage& image);
// Reads an 8-bit RGB (or grey) PNG; InputError(path, "png", ...) when it is not one.
RgbImage read_png(const std::filesystem::path& path);

// How two images of the same size differ: per-pixel largest channel difference (0..255).
struct ImageDifference {
  int max_channel_difference = 0;
  double mean_channel_difference = 0.0;  // over all channels of all pixels
  int64_t pixels_over_tolerance = 0;     // pixels with some channel differing by more than `tolerance`
  double fraction_over_tolerance = 0.0;  // of all pixels
};
// InputError("image comparison", "size", ...) when the sizes differ.
ImageDifference compare_images(const RgbImage& a, const RgbImage& b, int tolerance);

}  // namespace ctsurg

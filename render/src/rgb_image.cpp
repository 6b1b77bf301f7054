// OpenCV is confined to this file and image_composition.cpp.
#include "ctsurg/render/rgb_image.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdlib>

#include "ctsurg/core/error.h"

namespace ctsurg {

std::vector<uint8_t> encode_png(const RgbImage& image) {
  if (image.empty() || image.width <= 0 || image.height <= 0) throw RuntimeError("PNG: the image is empty");
  cv::Mat img(image.height, image.width, CV_8UC3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.pixel(x, y);
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(p[2], p[1], p[0]);  // OpenCV stores BGR
    }
  std::vector<uint8_t> bytes;
  if (!cv::imencode(".png", img, bytes, {cv::IMWRITE_PNG_COMPRESSION, 6})) throw RuntimeError("PNG: encoding failed");
  return bytes;
}

RgbImage read_png(const std::filesystem::path& path) {
  const cv::Mat img = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (img.empty() || img.depth() != CV_8U) throw InputError(path.string(), "png", "not a readable 8-bit PNG");
  RgbImage out(img.cols, img.rows);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b c = img.at<cv::Vec3b>(y, x);
      uint8_t* p = out.pixel(x, y);
      p[0] = c[2], p[1] = c[1], p[2] = c[0];
    }
  return out;
}

ImageDifference compare_images(const RgbImage& a, const RgbImage& b, int tolerance) {
  if (a.width != b.width || a.height != b.height) {
    throw InputError("image comparison", "size",
                     std::to_string(a.width) + " x " + std::to_string(a.height) + " against " + std::to_string(b.width) +
                         " x " + std::to_string(b.height));
  }
  ImageDifference d;
  const std::size_t pixels = static_cast<std::size_t>(a.width) * static_cast<std::size_t>(a.height);
  double sum = 0.0;
  for (std::size_t i = 0; i < pixels; ++i) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(int(a.rgb[3 * i + c]) - int(b.rgb[3 * i + c]));
      worst = std::max(worst, diff);
      sum += diff;
    }
    d.max_channel_difference = std::max(d.max_channel_difference, worst);
    if (worst > tolerance) ++d.pixels_over_tolerance;
  }
  d.mean_channel_difference = pixels ? sum / (3.0 * double(pixels)) : 0.0;
  d.fraction_over_tolerance = pixels ? double(d.pixels_over_tolerance) / double(pixels) : 0.0;
  return d;
}

}  // namespace ctsurg

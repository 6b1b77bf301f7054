// OpenCV is confined to this file; it turns normal maps into PNG bytes and back.
#include "ctsurg/mesh/normal_map_png.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ctsurg/core/error.h"

namespace ctsurg {

std::vector<uint8_t> encode_normal_map_png(const NormalMapImage& map) {
  if (map.empty()) throw RuntimeError("normal map PNG: the map is empty");
  const int w = static_cast<int>(map.width), h = static_cast<int>(map.height);
  cv::Mat img(h, w, map.bits == 16 ? CV_16UC3 : CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x));
      // OpenCV stores BGR.
      if (map.bits == 16)
        img.at<cv::Vec3w>(y, x) = cv::Vec3w(map.rgb[i + 2], map.rgb[i + 1], map.rgb[i]);
      else
        img.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uint8_t>(map.rgb[i + 2]), static_cast<uint8_t>(map.rgb[i + 1]),
                                            static_cast<uint8_t>(map.rgb[i]));
    }
  std::vector<uint8_t> bytes;
  if (!cv::imencode(".png", img, bytes, {cv::IMWRITE_PNG_COMPRESSION, 6})) throw RuntimeError("normal map PNG: encoding failed");
  return bytes;
}

NormalMapImage decode_normal_map_png(const std::vector<uint8_t>& png, const std::string& source) {
  const cv::Mat img = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  if (img.empty() || img.channels() != 3 || (img.depth() != CV_8U && img.depth() != CV_16U)) {
    throw InputError(source, "png", "not an RGB PNG with 8 or 16 bits per channel");
  }
  NormalMapImage map;
  map.width = img.cols;
  map.height = img.rows;
  map.bits = img.depth() == CV_16U ? 16 : 8;
  map.rgb.resize(3 * static_cast<std::size_t>(img.cols) * static_cast<std::size_t>(img.rows));
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(img.cols) + static_cast<std::size_t>(x));
      for (int c = 0; c < 3; ++c) {
        map.rgb[i + static_cast<std::size_t>(c)] =
            map.bits == 16 ? img.at<cv::Vec3w>(y, x)[2 - c] : static_cast<uint16_t>(img.at<cv::Vec3b>(y, x)[2 - c]);
      }
    }
  return map;
}

}  // namespace ctsurg

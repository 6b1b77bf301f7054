// OpenCV (drawing, Hershey text) is confined to this file and rgb_image.cpp.
#include "ctsurg/render/image_composition.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "ctsurg/core/error.h"
#include "ctsurg/render/colour_map.h"

namespace ctsurg {

namespace {

// Views an RgbImage as an OpenCV matrix (RGB order: colours below are given as RGB).
cv::Mat as_mat(RgbImage& image) { return cv::Mat(image.height, image.width, CV_8UC3, image.rgb.data()); }

double text_scale(int height) { return std::clamp(height / 400.0, 0.35, 1.2); }

std::string tick_label(double value, double step) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(step >= 1.0 ? 0 : step >= 0.1 ? 1 : step >= 0.01 ? 2 : 3);
  s << value;
  return s.str();
}

// A "nice" tick step (1, 2 or 5 x 10^k) giving about 5 intervals over [0, max].
double nice_step(double max) {
  const double raw = max / 5.0;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

}  // namespace

void draw_caption(RgbImage& image, const std::string& text) {
  if (text.empty() || image.empty()) return;
  cv::Mat m = as_mat(image);
  const double scale = text_scale(image.height);
  const int thickness = scale > 0.7 ? 2 : 1;
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  const int pad = std::max(2, int(std::lround(4 * scale)));
  cv::rectangle(m, cv::Rect(0, 0, std::min(image.width, size.width + 2 * pad), size.height + baseline + 2 * pad),
                cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(m, text, cv::Point(pad, pad + size.height), cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(255, 255, 255),
              thickness, cv::LINE_AA);
}

void draw_region_legend(RgbImage& image, const std::string& text, const float rgb[3]) {
  if (text.empty() || image.empty()) return;
  cv::Mat m = as_mat(image);
  double scale = text_scale(image.height);
  const int thickness = scale > 0.7 ? 2 : 1;
  int baseline = 0;
  cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  // Narrow pictures (a small side-by-side panel): smaller text, so the legend fits.
  const int room = image.width - 5 * std::max(2, int(std::lround(4 * scale))) - (size.height + baseline);
  if (size.width > room && room > 0) {
    scale = std::max(0.25, scale * room / size.width);
    size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  }
  const int pad = std::max(2, int(std::lround(4 * scale)));
  const int swatch = size.height + baseline;
  const int band_h = swatch + 2 * pad, y0 = std::max(0, image.height - band_h);
  cv::rectangle(m, cv::Rect(0, y0, std::min(image.width, swatch + size.width + 3 * pad), band_h), cv::Scalar(0, 0, 0), cv::FILLED);
  // The swatch: the region colour's stripes over a darker base, the interface as a dark line below.
  const int stripe = std::max(1, swatch / 5);
  for (int y = 0; y < swatch; ++y)
    for (int x = 0; x < swatch; ++x) {
      const int px = pad + x, py = y0 + pad + y;
      if (px >= image.width || py >= image.height) continue;
      const bool interface = y >= swatch - std::max(1, swatch / 6);
      const double w = interface ? 0.0 : ((x + y) / stripe) % 2 == 0 ? 1.0 : 0.5;
      uint8_t* p = image.pixel(px, py);
      for (int c = 0; c < 3; ++c) p[c] = static_cast<uint8_t>(std::lround(255.0 * std::clamp(double(rgb[c]), 0.0, 1.0) * w));
    }
  cv::putText(m, text, cv::Point(2 * pad + swatch, y0 + pad + size.height), cv::FONT_HERSHEY_SIMPLEX, scale,
              cv::Scalar(255, 255, 255), thickness, cv::LINE_AA);
}

RgbImage side_by_side(const std::vector<RgbImage>& images) {
  if (images.empty()) throw InputError("side by side", "images", "none given");
  constexpr int kGap = 4;
  int width = 0;
  for (const RgbImage& i : images) {
    if (i.height != images.front().height) throw InputError("side by side", "height", "the images differ in height");
    width += i.width;
  }
  width += kGap * int(images.size() - 1);
  RgbImage out(width, images.front().height, 255);
  int x0 = 0;
  for (const RgbImage& i : images) {
    for (int y = 0; y < i.height; ++y) std::memcpy(out.pixel(x0, y), i.pixel(0, y), 3 * static_cast<std::size_t>(i.width));
    x0 += i.width + kGap;
  }
  return out;
}

RgbImage overlay(const RgbImage& a, const RgbImage& b) {
  if (a.width != b.width || a.height != b.height) throw InputError("overlay", "size", "the images differ in size");
  RgbImage out(a.width, a.height);
  for (std::size_t i = 0; i < a.rgb.size(); ++i) out.rgb[i] = static_cast<uint8_t>((int(a.rgb[i]) + int(b.rgb[i]) + 1) / 2);
  return out;
}

RgbImage append_colour_bar(const RgbImage& image, double max_mm, const std::string& title) {
  const int h = image.height;
  const double scale = text_scale(h);
  const int bar_w = std::max(8, h / 24), margin_x = std::max(6, h / 40);
  const int label_w = int(std::lround(70 * scale)) + 8;
  const int panel_w = margin_x + bar_w + 6 + label_w;
  RgbImage out(image.width + panel_w, h, 255);
  for (int y = 0; y < h; ++y) std::memcpy(out.pixel(0, y), image.pixel(0, y), 3 * static_cast<std::size_t>(image.width));
  // Panel background: the picture's background colour (its top-left pixel) keeps the look uniform.
  const uint8_t* bg = image.pixel(0, 0);
  for (int y = 0; y < h; ++y)
    for (int x = image.width; x < out.width; ++x) std::memcpy(out.pixel(x, y), bg, 3);
  const int top = int(std::lround(h * 0.14)), bottom = int(std::lround(h * 0.92));
  const int x0 = image.width + margin_x;
  for (int y = top; y <= bottom; ++y) {
    const double t = double(bottom - y) / double(bottom - top);
    const auto c = turbo_colour(t);
    for (int x = x0; x < x0 + bar_w; ++x) std::memcpy(out.pixel(x, y), c.data(), 3);
  }
  cv::Mat m = as_mat(out);
  const cv::Scalar white(235, 235, 235);
  const int thickness = 1;
  cv::rectangle(m, cv::Rect(x0, top, bar_w, bottom - top + 1), white, 1);
  const double step = nice_step(max_mm);
  for (int k = 0;; ++k) {
    const double value = k * step;
    if (value > max_mm * (1.0 + 1e-9)) break;
    const int y = bottom - int(std::lround((bottom - top) * value / max_mm));
    cv::line(m, cv::Point(x0 + bar_w, y), cv::Point(x0 + bar_w + 4, y), white, 1);
    cv::putText(m, tick_label(value, step), cv::Point(x0 + bar_w + 7, y + int(5 * scale)), cv::FONT_HERSHEY_SIMPLEX,
                0.8 * scale, white, thickness, cv::LINE_AA);
  }
  // Title above the bar, right-aligned to the picture's edge so long titles stay inside.
  int baseline = 0;
  const double title_scale = 0.8 * scale;
  const cv::Size ts = cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, title_scale, thickness, &baseline);
  const int tx = std::max(0, out.width - ts.width - 4);
  cv::putText(m, title, cv::Point(tx, top - int(8 * scale) - 2), cv::FONT_HERSHEY_SIMPLEX, title_scale, white, thickness,
              cv::LINE_AA);
  return out;
}

}  // namespace ctsurg

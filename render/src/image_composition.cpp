// OpenCV (drawing, Hershey text) is confined to this file and rgb_image.cpp.
#include "ctsurg/render/image_composition.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

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
  double scale = text_scale(image.height);
  const int thickness = scale > 0.7 ? 2 : 1;
  int baseline = 0;
  cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  // Narrow pictures (a side-by-side panel, a small heat map): smaller text, so the caption fits.
  const int room = image.width - 2 * std::max(2, int(std::lround(4 * scale)));
  if (size.width > room && room > 0) {
    scale = std::max(0.25, scale * room / size.width);
    size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  }
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

// The title's words wrapped greedily into lines no wider than `width` pixels at `scale`.
static std::vector<std::string> wrapped_lines(const std::string& title, double scale, int thickness, int width) {
  std::vector<std::string> words, lines;
  std::istringstream in(title);
  for (std::string w; in >> w;) words.push_back(w);
  int baseline = 0;
  const auto width_of = [&](const std::string& t) {
    return cv::getTextSize(t, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline).width;
  };
  // A word wider than a line on its own (a long file name) is broken between characters.
  std::vector<std::string> pieces;
  for (const std::string& w : words) {
    std::string piece;
    for (const char c : w) {
      if (!piece.empty() && width_of(piece + c) > width) pieces.push_back(piece), piece.clear();
      piece += c;
    }
    pieces.push_back(piece);
  }
  words = pieces;
  for (const std::string& w : words) {
    const std::string joined = lines.empty() ? w : lines.back() + " " + w;
    if (!lines.empty() && width_of(joined) <= width)
      lines.back() = joined;
    else
      lines.push_back(w);
  }
  return lines;
}

RgbImage append_colour_bar(const RgbImage& image, double max_mm, const std::string& title) {
  const int h = image.height;
  const double scale = text_scale(h);
  const int thickness = 1;
  const int bar_w = std::max(8, h / 24), margin_x = std::max(6, h / 40);
  const int label_w = int(std::lround(70 * scale)) + 8;
  // The title sits in the panel, above the bar, never over the picture: the panel widens (up to twice
  // its width) for the title's longest word, the text shrinks (down to 0.6x) when even that is too
  // narrow, and lines wrap at word boundaries (a longer word, a file name, between characters).
  double title_scale = 0.8 * scale;
  int baseline = 0;
  int longest_word = 0;
  {
    std::istringstream in(title);
    for (std::string w; in >> w;)
      longest_word = std::max(longest_word, cv::getTextSize(w, cv::FONT_HERSHEY_SIMPLEX, title_scale, thickness, &baseline).width);
  }
  const int base_panel_w = margin_x + bar_w + 6 + label_w;
  const int panel_w = std::max(base_panel_w, std::min(longest_word + 4, 2 * base_panel_w));
  const int title_room = panel_w - 4;
  if (longest_word > title_room) title_scale = std::max(0.6 * title_scale, title_scale * title_room / longest_word);
  const std::vector<std::string> lines = wrapped_lines(title, title_scale, thickness, title_room);
  const int line_h = cv::getTextSize("Ag", cv::FONT_HERSHEY_SIMPLEX, title_scale, thickness, &baseline).height + baseline + 2;
  const int title_h = int(lines.size()) * line_h;
  const int top = std::max(int(std::lround(h * 0.14)), title_h + int(std::lround(8 * scale)) + 2);
  const int bottom = std::max(top + 8, int(std::lround(h * 0.92)));
  RgbImage out(image.width + panel_w, h, 255);
  for (int y = 0; y < h; ++y) std::memcpy(out.pixel(0, y), image.pixel(0, y), 3 * static_cast<std::size_t>(image.width));
  // Panel background: the picture's background colour (its top-left pixel) keeps the look uniform.
  const uint8_t* bg = image.pixel(0, 0);
  for (int y = 0; y < h; ++y)
    for (int x = image.width; x < out.width; ++x) std::memcpy(out.pixel(x, y), bg, 3);
  const int x0 = image.width + margin_x;
  for (int y = top; y <= bottom && y < h; ++y) {
    const double t = double(bottom - y) / double(bottom - top);
    const auto c = turbo_colour(t);
    for (int x = x0; x < x0 + bar_w; ++x) std::memcpy(out.pixel(x, y), c.data(), 3);
  }
  cv::Mat m = as_mat(out);
  const cv::Scalar white(235, 235, 235);
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
  // Each title line left-aligned at the panel's inner edge (clipped to the panel by construction).
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const int y = int(i + 1) * line_h - baseline + 1;
    cv::putText(m, lines[i], cv::Point(image.width + 2, y), cv::FONT_HERSHEY_SIMPLEX, title_scale, white, thickness,
                cv::LINE_AA);
  }
  return out;
}

}  // namespace ctsurg

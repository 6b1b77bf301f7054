#include "ctsurg/mesh/centerline_preview.h"

#include "ctsurg/core/error.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace ctsurg {

namespace {

constexpr int kMarginPx = 12;
constexpr int kLegendPx = 34;
constexpr int kMinWidthPx = 470;

// Blue -> cyan -> green -> yellow -> red for t in [0, 1], as BGR.
cv::Scalar ramp(double t) {
  t = std::clamp(t, 0.0, 1.0);
  static const std::array<std::array<double, 3>, 5> rgb{{{40, 60, 230}, {0, 200, 230}, {40, 210, 60}, {240, 220, 20}, {230, 40, 30}}};
  const double x = t * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  std::array<double, 3> c{};
  for (std::size_t k = 0; k < 3; ++k) c[k] = (1.0 - f) * rgb[static_cast<std::size_t>(i)][k] + f * rgb[static_cast<std::size_t>(i + 1)][k];
  return cv::Scalar(c[2], c[1], c[0]);
}

}  // namespace

std::vector<uint8_t> render_centerline_preview_png(const Volume<uint8_t>& mask, const Centerline& cl, int size_px) {
  const ImageGeometry& g = mask.geometry;
  const Eigen::Matrix3d m = g.index_to_world_matrix();
  // A voxel's footprint on the (x, z) picture plane and its depth along y.
  const double half_x = 0.5 * (m.row(0).cwiseAbs().sum()), half_z = 0.5 * (m.row(2).cwiseAbs().sum());
  const double depth = g.voxel_volume_mm3() / (4.0 * half_x * half_z);
  double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
  const auto extend = [&](double x, double z) {
    x0 = std::min(x0, x - half_x);
    x1 = std::max(x1, x + half_x);
    z0 = std::min(z0, z - half_z);
    z1 = std::max(z1, z + half_z);
  };
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        if (!mask.voxels[static_cast<std::size_t>(g.flat_index(i, j, k))]) continue;
        const Eigen::Vector3d p = g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)));
        extend(p.x(), p.z());
      }
  for (std::size_t p = 0; p + 2 < cl.points.size(); p += 3) extend(cl.points[p], cl.points[p + 2]);
  const double extent = std::max({x1 - x0, z1 - z0, 1e-3});
  const double mm_per_px = extent / size_px;
  // At least wide enough for the legend: a narrow vessel is drawn centred.
  const int drawn_w = static_cast<int>(std::ceil((x1 - x0) / mm_per_px)) + 2 * kMarginPx;
  const int w = std::max(drawn_w, kMinWidthPx), pad = (w - drawn_w) / 2;
  const int h = static_cast<int>(std::ceil((z1 - z0) / mm_per_px)) + 2 * kMarginPx;
  const auto px = [&](double x, double z) {
    return cv::Point2d(pad + kMarginPx + (x - x0) / mm_per_px, kMarginPx + (z1 - z) / mm_per_px);
  };

  cv::Mat thickness(h, w, CV_32F, cv::Scalar(0));
  for (int64_t k = 0; k < g.dims[2]; ++k)
    for (int64_t j = 0; j < g.dims[1]; ++j)
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        if (!mask.voxels[static_cast<std::size_t>(g.flat_index(i, j, k))]) continue;
        const Eigen::Vector3d p = g.index_to_world(Eigen::Vector3d(double(i), double(j), double(k)));
        const cv::Point2d a = px(p.x() - half_x, p.z() + half_z), b = px(p.x() + half_x, p.z() - half_z);
        const int u0 = std::max(0, static_cast<int>(std::lround(a.x))), u1 = std::min(w, static_cast<int>(std::lround(b.x)));
        const int v0 = std::max(0, static_cast<int>(std::lround(a.y))), v1 = std::min(h, static_cast<int>(std::lround(b.y)));
        for (int v = v0; v < std::max(v1, v0 + 1) && v < h; ++v)
          for (int u = u0; u < std::max(u1, u0 + 1) && u < w; ++u) thickness.at<float>(v, u) += static_cast<float>(depth);
      }
  double max_thickness = 0.0;
  cv::minMaxLoc(thickness, nullptr, &max_thickness);
  cv::Mat img(h + kLegendPx, w, CV_8UC3, cv::Scalar(0, 0, 0));
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const float t = thickness.at<float>(v, u);
      if (t <= 0.0f) continue;
      const auto grey = static_cast<uint8_t>(60.0 + 150.0 * std::min(1.0, double(t) / std::max(max_thickness, 1e-9)));
      img.at<cv::Vec3b>(v, u) = cv::Vec3b(grey, grey, grey);
    }

  double r0 = 1e300, r1 = 0.0;
  for (const double r : cl.radius) {
    r0 = std::min(r0, r);
    r1 = std::max(r1, r);
  }
  const auto colour = [&](double r) { return ramp(r1 > r0 ? (r - r0) / (r1 - r0) : 0.5); };
  constexpr int kShift = 4;  // sub-pixel drawing: coordinates in 1/16 px
  const auto fixed = [&](const cv::Point2d& p) { return cv::Point(static_cast<int>(std::lround(p.x * 16)), static_cast<int>(std::lround(p.y * 16))); };
  const int line_px = std::max(2, size_px / 256);
  for (int64_t b = 0; b < cl.branch_count(); ++b) {
    for (int64_t p = cl.branch_offsets[static_cast<std::size_t>(b)] + 1; p < cl.branch_offsets[static_cast<std::size_t>(b + 1)]; ++p) {
      const auto q = static_cast<std::size_t>(3 * p);
      const cv::Point2d a = px(cl.points[q - 3], cl.points[q - 1]), c = px(cl.points[q], cl.points[q + 2]);
      const double r = 0.5 * (cl.radius[static_cast<std::size_t>(p - 1)] + cl.radius[static_cast<std::size_t>(p)]);
      cv::line(img, fixed(a), fixed(c), colour(r), line_px, cv::LINE_AA, kShift);
    }
  }
  std::vector<int> degree(static_cast<std::size_t>(cl.node_count()), 0);
  for (const int32_t n : cl.branch_nodes) ++degree[static_cast<std::size_t>(n)];
  for (int64_t n = 0; n < cl.node_count(); ++n) {
    const auto q = static_cast<std::size_t>(3 * n);
    const cv::Point c = fixed(px(cl.nodes[q], cl.nodes[q + 2]));
    const int s = 5 * 16;
    if (degree[static_cast<std::size_t>(n)] >= 3) {
      cv::rectangle(img, cv::Point(c.x - s, c.y - s), cv::Point(c.x + s, c.y + s), cv::Scalar(255, 0, 255), cv::FILLED,
                    cv::LINE_AA, kShift);
    } else {
      cv::circle(img, c, s, cv::Scalar(255, 255, 255), 2, cv::LINE_AA, kShift);
    }
  }

  // Legend: the radius colour bar and what the marks mean.
  const int bar_w = std::min(160, w / 3), y = h + 8;
  for (int u = 0; u < bar_w; ++u) cv::line(img, cv::Point(8 + u, y), cv::Point(8 + u, y + 8), ramp(double(u) / std::max(1, bar_w - 1)));
  char text[160];
  std::snprintf(text, sizeof text, "radius %.1f .. %.1f mm   o end  # junction   anterior view, R on left", r0, r1);
  cv::putText(img, text, cv::Point(8, y + 22), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);

  std::vector<uint8_t> bytes;
  if (!cv::imencode(".png", img, bytes, {cv::IMWRITE_PNG_COMPRESSION, 6})) throw RuntimeError("centerline preview PNG: encoding failed");
  return bytes;
}

}  // namespace ctsurg

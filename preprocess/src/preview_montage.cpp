// OpenCV is confined to this file; it returns plain RGB images and PNG bytes.
#include "ctsurg/preprocess/preview_montage.h"

#include "ctsurg/core/error.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ctsurg {

namespace {

constexpr int kLabelStripPx = 20;  // text above each tile
constexpr int kTitleStripPx = 24;  // legend above the montage
constexpr int kGapPx = 4;

cv::Scalar bgr(const uint8_t rgb[3]) { return cv::Scalar(rgb[2], rgb[1], rgb[0]); }

void outline(cv::Mat& tile, const cv::Mat& binary, const cv::Scalar& colour, int thickness = 1) {
  std::vector<std::vector<cv::Point>> contours;
  cv::Mat work = binary.clone();  // findContours may modify its input in older OpenCV versions
  cv::findContours(work, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  cv::drawContours(tile, contours, -1, colour, thickness, cv::LINE_8);
}

}  // namespace

std::vector<int64_t> preview_slice_indices(const Volume<uint16_t>& mask, int count) {
  const auto& d = mask.geometry.dims;
  int64_t k0 = d[2], k1 = -1;
  const int64_t plane = d[0] * d[1];
  for (int64_t k = 0; k < d[2]; ++k) {
    const auto first = mask.voxels.begin() + plane * k;
    if (std::any_of(first, first + plane, [](uint16_t v) { return v != 0; })) {
      k0 = std::min(k0, k);
      k1 = k;
    }
  }
  std::vector<int64_t> ks;
  if (k1 < 0 || count < 1) return ks;
  const int64_t extent = k1 - k0 + 1;
  for (int s = 0; s < count; ++s) {
    const int64_t k = k0 + static_cast<int64_t>(std::floor((s + 0.5) * double(extent) / count));
    if (ks.empty() || ks.back() != k) ks.push_back(k);
  }
  return ks;
}

RgbImage render_preview_montage(const Volume<float>& hu, const Volume<uint16_t>& mask,
                                const Volume<uint8_t>& occupancy, const PreviewOptions& options) {
  if (!hu.geometry.same_lattice(mask.geometry)) throw RuntimeError("preview: the mask is not on the CT lattice");
  const auto slices = preview_slice_indices(mask, options.slices);
  if (slices.empty()) throw RuntimeError("preview: the mask is empty");
  const ImageGeometry& g = hu.geometry;
  const int nx = static_cast<int>(g.dims[0]), ny = static_cast<int>(g.dims[1]);
  // One scale (pixels per mm) for every tile, keeping the physical aspect ratio.
  const double px_per_mm = options.tile_width_px / (nx * g.spacing[0]);
  const int tw = std::max(1, static_cast<int>(std::lround(nx * g.spacing[0] * px_per_mm)));
  const int th = std::max(1, static_cast<int>(std::lround(ny * g.spacing[1] * px_per_mm)));
  const int columns = std::max(1, std::min<int>(options.columns, static_cast<int>(slices.size())));
  const int rows = static_cast<int>((slices.size() + size_t(columns) - 1) / size_t(columns));
  const int cell_w = tw + kGapPx, cell_h = th + kLabelStripPx + kGapPx;
  cv::Mat montage(kTitleStripPx + rows * cell_h, columns * cell_w + kGapPx, CV_8UC3, cv::Scalar(24, 24, 24));

  char text[160];
  std::snprintf(text, sizeof text, "CT W%g L%g   green: tissue mask   magenta: particles   radiological: patient right on the left",
                options.window_width, options.window_level);
  cv::putText(montage, text, cv::Point(kGapPx, 17), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);

  const double lo = options.window_level - 0.5 * options.window_width;
  const double width = std::max(options.window_width, 1e-6);
  const Eigen::Matrix3d ct_to_world = g.index_to_world_matrix();
  // Radiological display whatever the storage order: mirror i when it runs towards patient right
  // (-x LPS) and j when it runs anterior (-y LPS), e.g. for NIfTI data stored in RAS order.
  const bool flip_i = g.direction(0, 0) < 0.0, flip_j = g.direction(1, 1) < 0.0;
  for (size_t s = 0; s < slices.size(); ++s) {
    const int64_t k = slices[s];
    cv::Mat hu_slice(ny, nx, CV_32F, const_cast<float*>(hu.voxels.data() + size_t(int64_t(nx) * ny * k)));
    cv::Mat hu_tile;
    cv::resize(hu_slice, hu_tile, cv::Size(tw, th), 0, 0, cv::INTER_LINEAR);
    if (flip_i || flip_j) cv::flip(hu_tile, hu_tile, flip_i && flip_j ? -1 : flip_i ? 1 : 0);
    cv::Mat grey(th, tw, CV_8U);
    for (int y = 0; y < th; ++y)
      for (int x = 0; x < tw; ++x) {
        const double v = (hu_tile.at<float>(y, x) - lo) / width * 255.0;
        grey.at<uint8_t>(y, x) = static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L));
      }
    cv::Mat tile;
    cv::cvtColor(grey, tile, cv::COLOR_GRAY2BGR);

    // Nearest-voxel mask and nearest-cell particle rasters at tile resolution.
    cv::Mat in_mask(th, tw, CV_8U, cv::Scalar(0)), in_particle(th, tw, CV_8U, cv::Scalar(0));
    const auto& od = occupancy.geometry.dims;
    for (int y = 0; y < th; ++y) {
      double fj = (y + 0.5) * ny / th - 0.5;
      if (flip_j) fj = (ny - 1) - fj;
      const int j = std::clamp(static_cast<int>(std::lround(fj)), 0, ny - 1);
      for (int x = 0; x < tw; ++x) {
        double fi = (x + 0.5) * nx / tw - 0.5;
        if (flip_i) fi = (nx - 1) - fi;
        const int i = std::clamp(static_cast<int>(std::lround(fi)), 0, nx - 1);
        if (mask(i, j, k) != 0) in_mask.at<uint8_t>(y, x) = 255;
        const Eigen::Vector3d world = g.origin + ct_to_world * Eigen::Vector3d(fi, fj, double(k));
        const Eigen::Vector3d c = occupancy.geometry.world_to_index(world);
        const int64_t ci = std::llround(c[0]), cj = std::llround(c[1]), ck = std::llround(c[2]);
        if (ci >= 0 && cj >= 0 && ck >= 0 && ci < od[0] && cj < od[1] && ck < od[2] && occupancy(ci, cj, ck)) {
          in_particle.at<uint8_t>(y, x) = 255;
        }
      }
    }
    outline(tile, in_particle, bgr(kParticleOutlineRgb), 2);  // under the 1 px mask line, so both show
    outline(tile, in_mask, bgr(kMaskOutlineRgb));

    const int col = static_cast<int>(s) % columns, row = static_cast<int>(s) / columns;
    const int x0 = kGapPx + col * cell_w, y0 = kTitleStripPx + row * cell_h;
    tile.copyTo(montage(cv::Rect(x0, y0 + kLabelStripPx, tw, th)));
    const Eigen::Vector3d centre = g.index_to_world(Eigen::Vector3d(0.5 * (nx - 1), 0.5 * (ny - 1), double(k)));
    std::snprintf(text, sizeof text, "k %lld   z %.1f mm", static_cast<long long>(k), centre.z());
    cv::putText(montage, text, cv::Point(x0 + 2, y0 + 15), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255), 1,
                cv::LINE_AA);
  }

  RgbImage image;
  image.width = montage.cols;
  image.height = montage.rows;
  cv::Mat rgb;
  cv::cvtColor(montage, rgb, cv::COLOR_BGR2RGB);
  image.rgb.assign(rgb.data, rgb.data + size_t(rgb.total()) * 3);
  return image;
}

std::string encode_png(const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != size_t(image.width) * size_t(image.height) * 3) {
    throw RuntimeError("encode_png: image size does not match its pixel buffer");
  }
  cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.rgb.data()));
  cv::Mat bgr_image;
  cv::cvtColor(rgb, bgr_image, cv::COLOR_RGB2BGR);
  std::vector<uchar> bytes;
  if (!cv::imencode(".png", bgr_image, bytes, {cv::IMWRITE_PNG_COMPRESSION, 6})) {
    throw RuntimeError("encode_png: PNG encoding failed");
  }
  return std::string(bytes.begin(), bytes.end());
}

}  // namespace ctsurg

#include "ctsurg/preprocess/preview_montage.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ctsurg {
namespace {

struct Phantom {
  Volume<float> hu;
  Volume<uint16_t> mask;
  Volume<uint8_t> occupancy;
};

// A 60 x 50 x 40 CT (1 mm) with a +60 HU box in -1000 HU air; mask = the box (i 20..39, j 10..29,
// k 5..34); occupancy = one 10 mm cell lattice with particles over the box.
Phantom phantom() {
  Phantom p;
  ImageGeometry g;
  g.dims = {60, 50, 40};
  p.hu = Volume<float>(g, -1000.0f);
  p.mask = Volume<uint16_t>(g, 0);
  for (int64_t k = 5; k < 35; ++k)
    for (int64_t j = 10; j < 30; ++j)
      for (int64_t i = 20; i < 40; ++i) {
        p.hu(i, j, k) = 60.0f;
        p.mask(i, j, k) = 1;
      }
  ImageGeometry c;
  c.dims = {6, 5, 4};
  c.spacing = Eigen::Vector3d::Constant(10.0);
  c.origin = Eigen::Vector3d(4.5, 4.5, 4.5);  // cell (i) spans [10 i - 0.5, 10 i + 9.5] in CT index
  p.occupancy = Volume<uint8_t>(c, 0);
  for (int64_t k = 0; k < 4; ++k)
    for (int64_t j = 1; j < 3; ++j)
      for (int64_t i = 2; i < 4; ++i) p.occupancy(i, j, k) = 1;
  return p;
}

bool is(const uint8_t* px, const uint8_t rgb[3]) { return px[0] == rgb[0] && px[1] == rgb[1] && px[2] == rgb[2]; }

TEST(PreviewMontage, SliceIndicesSpreadOverTheMask) {
  const auto p = phantom();
  const auto ks = preview_slice_indices(p.mask, 12);
  ASSERT_EQ(ks.size(), 12u);
  EXPECT_GE(ks.front(), 5);
  EXPECT_LE(ks.back(), 34);
  for (size_t n = 1; n < ks.size(); ++n) EXPECT_GT(ks[n], ks[n - 1]);
  EXPECT_EQ(preview_slice_indices(p.mask, 100).size(), 30u);  // at most one per slice
  EXPECT_TRUE(preview_slice_indices(Volume<uint16_t>(p.mask.geometry, 0), 12).empty());
}

TEST(PreviewMontage, DrawsWindowedCtAndBothOutlines) {
  const auto p = phantom();
  PreviewOptions o;
  o.slices = 4;
  o.columns = 2;
  o.tile_width_px = 120;  // 2 px per mm
  const RgbImage img = render_preview_montage(p.hu, p.mask, p.occupancy, o);
  ASSERT_EQ(img.rgb.size(), size_t(img.width) * img.height * 3);
  EXPECT_GE(img.width, 2 * 120);
  EXPECT_GE(img.height, 2 * 100);
  int64_t green = 0, magenta = 0, tissue_grey = 0, black = 0;
  const int expected_grey = int(std::lround((60.0 - (40.0 - 200.0)) / 400.0 * 255.0));  // 140
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const uint8_t* px = img.pixel(x, y);
      green += is(px, kMaskOutlineRgb);
      magenta += is(px, kParticleOutlineRgb);
      tissue_grey += px[0] == expected_grey && px[1] == expected_grey && px[2] == expected_grey;
      black += px[0] == 0 && px[1] == 0 && px[2] == 0;
    }
  // Box outline: 4 tiles x perimeter 2 x (40 + 40) px; particles outline a 20 x 20 mm square too.
  EXPECT_GT(green, 4 * 100);
  EXPECT_GT(magenta, 4 * 100);
  EXPECT_GT(tissue_grey, 4 * 30 * 30);  // tissue at W400/L40
  EXPECT_GT(black, 4 * 60 * 40);        // air below the window
  // First tile (top left): the mask's left edge x = 20 mm is at tile pixel 40, the right edge at 80.
  // Find the tile's top by the first row holding green.
  int top = -1;
  for (int y = 0; y < img.height && top < 0; ++y)
    for (int x = 0; x < img.width / 2; ++x)
      if (is(img.pixel(x, y), kMaskOutlineRgb)) {
        top = y;
        break;
      }
  ASSERT_GE(top, 0);
  int left = img.width, right = -1;
  for (int x = 0; x < img.width / 2; ++x)
    if (is(img.pixel(x, top + 10), kMaskOutlineRgb)) {
      left = std::min(left, x);
      right = std::max(right, x);
    }
  EXPECT_NEAR(right - left, 39, 2);  // 20 mm at 2 px/mm, contour on the inner pixels
}

TEST(PreviewMontage, PngIsDeterministicAndValid) {
  const auto p = phantom();
  const auto a = encode_png(render_preview_montage(p.hu, p.mask, p.occupancy, {}));
  const auto b = encode_png(render_preview_montage(p.hu, p.mask, p.occupancy, {}));
  EXPECT_EQ(a, b);
  ASSERT_GT(a.size(), 8u);
  EXPECT_EQ(a.substr(1, 3), "PNG");
}

TEST(PreviewMontage, RejectsMismatchedOrEmptyMask) {
  const auto p = phantom();
  ImageGeometry other = p.mask.geometry;
  other.dims = {10, 10, 10};
  EXPECT_ANY_THROW(render_preview_montage(p.hu, Volume<uint16_t>(other, 1), p.occupancy, {}));
  EXPECT_ANY_THROW(render_preview_montage(p.hu, Volume<uint16_t>(p.mask.geometry, 0), p.occupancy, {}));
}

}  // namespace
}  // namespace ctsurg

// Tests render/include/ctsurg/render/image_composition.h: captions, the colour bar's panel (its title
// never over the picture), side by side and overlays.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "ctsurg/core/error.h"
#include "ctsurg/render/image_composition.h"

namespace {

using ctsurg::RgbImage;

// A picture with a distinct pattern, so "unchanged" is a real check: a gradient over a dark background.
RgbImage pattern(int w, int h) {
  RgbImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = img.pixel(x, y);
      p[0] = static_cast<uint8_t>(20 + (x * 3) % 100);
      p[1] = static_cast<uint8_t>(20 + (y * 5) % 100);
      p[2] = static_cast<uint8_t>(30);
    }
  return img;
}

bool bright(const uint8_t* p) { return p[0] > 180 && p[1] > 180 && p[2] > 180; }

// Rows [y0, y1) of columns [x0, x1): how many pixels are bright (text).
int bright_pixels(const RgbImage& img, int x0, int x1, int y0, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += bright(img.pixel(x, y));
  return n;
}

TEST(ImageComposition, ColourBarTitleStaysInItsPanelHoweverLong) {
  for (const int h : {160, 300, 512}) {
    const RgbImage img = pattern(h, h);
    for (const std::string title : {std::string("displacement (mm)"),
                                    std::string("difference from heart_explicit_grab_on_the_gpu_run (mm)")}) {
      SCOPED_TRACE(std::to_string(h) + " " + title);
      const RgbImage out = ctsurg::append_colour_bar(img, 20.0, title);
      ASSERT_EQ(out.height, h);
      ASSERT_GT(out.width, img.width);
      // The picture is untouched: the title (the old bug) was drawn over its top-right corner.
      for (int y = 0; y < h; ++y)
        ASSERT_TRUE(std::equal(img.pixel(0, y), img.pixel(0, y) + 3 * img.width, out.pixel(0, y))) << "row " << y;
      // The title is in the panel, in its top rows above the bar's first coloured row.
      int bar_top = -1;
      for (int y = 0; y < h && bar_top < 0; ++y)
        for (int x = img.width; x < out.width; ++x) {
          const uint8_t* p = out.pixel(x, y);
          if (std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]}) > 60) {  // saturated: Turbo
            bar_top = y;
            break;
          }
        }
      ASSERT_GT(bar_top, 0);
      EXPECT_GT(bright_pixels(out, img.width, out.width, 0, bar_top), 10);
      // Nothing is cut at the panel's right edge: the last column above the bar holds no text.
      EXPECT_EQ(bright_pixels(out, out.width - 1, out.width, 0, bar_top), 0);
    }
  }
}

TEST(ImageComposition, ColourBarRunsFromBlueAtZeroToRedAtTheTop) {
  const RgbImage img = pattern(200, 200);
  const RgbImage out = ctsurg::append_colour_bar(img, 5.0, "displacement (mm)");
  // The bar's centre column: find the coloured rows, then compare the ends.
  int x_bar = -1, first = -1, last = -1;
  for (int x = img.width; x < out.width && x_bar < 0; ++x)
    for (int y = 0; y < out.height; ++y) {
      const uint8_t* p = out.pixel(x, y);
      if (std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]}) > 60) {
        x_bar = x + 3;
        break;
      }
    }
  ASSERT_GE(x_bar, 0);
  for (int y = 0; y < out.height; ++y) {
    const uint8_t* p = out.pixel(x_bar, y);
    if (std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]}) > 60) {
      if (first < 0) first = y;
      last = y;
    }
  }
  ASSERT_GT(last - first, out.height / 2);
  const uint8_t* top = out.pixel(x_bar, first + 2);
  const uint8_t* bottom = out.pixel(x_bar, last - 2);
  EXPECT_GT(top[0], top[2]);        // red above
  EXPECT_GT(bottom[2], bottom[0]);  // blue (Turbo's dark blue-violet) below
}

TEST(ImageComposition, CaptionShrinksToFitANarrowPicture) {
  const std::string text = "heart_grab: frame 40, t = 0.800 s";
  for (const int w : {120, 160, 400}) {
    SCOPED_TRACE(w);
    RgbImage img = pattern(w, 160);
    ctsurg::draw_caption(img, text);
    EXPECT_GT(bright_pixels(img, 0, w, 0, 40), 20);
    // The text ends inside the picture: its last columns hold no text pixels.
    EXPECT_EQ(bright_pixels(img, w - 2, w, 0, 40), 0);
  }
}

TEST(ImageComposition, SideBySideAndOverlayKeepPixelsAndRefuseMismatchedSizes) {
  const RgbImage a = pattern(30, 20), b(25, 20, 200);
  const RgbImage s = ctsurg::side_by_side({a, b});
  ASSERT_EQ(s.height, 20);
  ASSERT_EQ(s.width, 30 + 4 + 25);
  EXPECT_TRUE(std::equal(a.pixel(0, 7), a.pixel(0, 7) + 3 * 30, s.pixel(0, 7)));
  EXPECT_EQ(s.pixel(34, 7)[1], 200);
  EXPECT_THROW(ctsurg::side_by_side({a, RgbImage(10, 21)}), ctsurg::InputError);
  EXPECT_THROW(ctsurg::side_by_side({}), ctsurg::InputError);

  const RgbImage o = ctsurg::overlay(RgbImage(4, 4, 100), RgbImage(4, 4, 201));
  EXPECT_EQ(o.pixel(2, 3)[0], 151);
  EXPECT_THROW(ctsurg::overlay(RgbImage(4, 4), RgbImage(5, 4)), ctsurg::InputError);
}

}  // namespace

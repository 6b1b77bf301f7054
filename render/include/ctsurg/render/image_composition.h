// Comparison pictures from rendered images: side by side with captions, overlays, and the colour bar
// of a heat map with its scale in millimetres. Text through OpenCV's Hershey fonts (deterministic,
// no font files), confined to image_composition.cpp.
#pragma once

#include <string>
#include <vector>

#include "ctsurg/render/rgb_image.h"

namespace ctsurg {

// Writes `text` in white on a dark band at the top-left corner of `image` (scaled to its size, and
// smaller, down to a 0.25 font scale, where the picture is too narrow for it).
void draw_caption(RgbImage& image, const std::string& text);
// Writes a legend entry at the bottom-left corner of `image`: on a dark band, a swatch of `rgb` hatched as
// the renderer hatches the FEM local region (surface_renderer.h) with a dark interface line under it,
// then `text` in white (scaled to the image's size).
void draw_region_legend(RgbImage& image, const std::string& text, const float rgb[3]);
// The images (same height) left to right with a 4-pixel separator. InputError when heights differ.
RgbImage side_by_side(const std::vector<RgbImage>& images);
// a and b (same size) blended: each pixel (a + b) / 2, so the two shapes show through each other
// (render them in different colours). InputError when sizes differ.
RgbImage overlay(const RgbImage& a, const RgbImage& b);
// `image` widened on the right by a vertical Turbo colour bar from 0 (bottom) to max_mm (top) with
// tick labels in mm and `title` (e.g. "displacement (mm)") above the bar, inside the added panel:
// the panel widens (up to 2x) for the title's longest word, the text shrinks (down to 0.6x) when that
// is not enough, and lines wrap at spaces (a longer word between characters). Nothing is drawn over
// `image`.
RgbImage append_colour_bar(const RgbImage& image, double max_mm, const std::string& title);

}  // namespace ctsurg

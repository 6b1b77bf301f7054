// The picture that shows whether a centerline is right at a glance (OpenCV is confined to
// centerline_preview.cpp): the mask seen from the front (anterior view: LPS x to the right of the
// picture, so the patient's right is on its left, superior up), grey by the mask's thickness along
// the view (a projection of the mask; its outline is the maximum-intensity projection), with the
// centerline drawn over it coloured by radius (blue thin .. red thick, legend at the bottom), end
// points as white rings and junctions as magenta squares. PNG without time stamps: the same input
// gives the same bytes.
#pragma once

#include "ctsurg/core/centerline_file.h"
#include "ctsurg/core/volume.h"

#include <cstdint>
#include <vector>

namespace ctsurg {

// PNG bytes of the preview.
//   mask        the mask the centerline came from (non-zero = inside), LPS mm geometry
//   centerline  its centerline (LPS mm)
//   size_px     the longer side of the drawing area, pixels (the legend strip is added below)
// RuntimeError when the encoder fails.
std::vector<uint8_t> render_centerline_preview_png(const Volume<uint8_t>& mask, const Centerline& centerline,
                                                   int size_px = 640);

}  // namespace ctsurg

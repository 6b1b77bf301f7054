// Tissue selection: which full-resolution CT voxels are the organ. Three methods, each returning a
// label mask on the CT lattice (Volume<uint16_t>, x fastest, 0 = background, else the tissue label):
//  - an HU window [hu_min, hu_max] (label 1),
//  - Otsu's threshold on the HU histogram (label 1),
//  - a label volume on the same lattice (e.g. a segmentation), keeping the chosen label ids.
#pragma once

#include "ctsurg/core/volume.h"

#include <cstdint>
#include <string>
#include <vector>

namespace ctsurg {

// Voxels with hu_min <= HU <= hu_max get `label`, the others 0.
//   hu     CT volume, HU, any lattice
//   file   name of the CT file, used in error messages
// Returns a mask on hu's lattice. InputError(file, "--hu-min/--hu-max", ...) when the window is
// empty (hu_min > hu_max) or selects no voxel; the message gives the window and the volume's HU
// range.
Volume<uint16_t> select_hu_window(const Volume<float>& hu, double hu_min, double hu_max, const std::string& file,
                                  uint16_t label = 1);

// Otsu's threshold (N. Otsu, "A threshold selection method from gray-level histograms", IEEE SMC
// 9(1), 1979): the HU value t that maximises the between-class variance
// w0(t) w1(t) (mu0(t) - mu1(t))^2 over a histogram of `bins` equal-width bins spanning
// [min HU, max HU]. Returns the upper edge of the last background bin, in HU; voxels > t are the
// foreground. Deterministic (ties keep the lowest bin). RuntimeError for an empty volume;
// InputError(file, "--otsu", ...) for a constant volume (no threshold exists).
double otsu_threshold(const Volume<float>& hu, const std::string& file, int bins = 256);

// Voxels with HU > otsu_threshold(hu) get `label`.
Volume<uint16_t> select_otsu(const Volume<float>& hu, const std::string& file, uint16_t label = 1);

// Converts a label volume (values as read, float) to a tissue mask keeping only `ids` (all
// non-zero labels when `ids` is empty).
//   labels  label volume; every value must be an integer in [0, 65535]
//   file    its file name, for error messages
// InputError(file, "labels", ...) for a non-integer or out-of-range value (names the first voxel),
// and InputError(file, "--labels", ...) when nothing is selected (lists the labels present).
Volume<uint16_t> select_labels(const Volume<float>& labels, const std::vector<uint16_t>& ids, const std::string& file);

// Sorted distinct non-zero labels of a mask.
std::vector<uint16_t> labels_present(const Volume<uint16_t>& mask);

// Number of non-zero voxels of a mask.
int64_t count_tissue_voxels(const Volume<uint16_t>& mask);

}  // namespace ctsurg

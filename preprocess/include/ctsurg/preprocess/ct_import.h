// CT import: any supported input (a DICOM series folder, NIfTI, NRRD with attached or detached
// data, MetaImage) to an HU volume in LPS mm with exact geometry.
#pragma once

#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/preprocess/dicom_series_reader.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace ctsurg {

struct CtImportOptions {
  DicomReadOptions dicom;
  // Applied to non-DICOM inputs whose stored values are not HU (e.g. HU + 1024 in raw exports):
  // HU = stored x slope + intercept. DICOM carries its own RescaleSlope/Intercept.
  std::optional<double> rescale_slope, rescale_intercept;
};

struct CtImport {
  HuVolume volume;
  std::vector<std::filesystem::path> files;  // every file the volume was read from (for provenance)
  std::vector<std::string> warnings;         // geometry and value warnings, with numbers
};

CtImport import_ct(const std::filesystem::path& input, const CtImportOptions& options);

// The data files a detached header points to, resolved against the header's folder: NRRD
// ("data file:") and MetaImage ("ElementDataFile ="), each as a single name, a printf-style pattern
// with min max step, or LIST followed by names. Empty for attached data (and MetaImage LOCAL).
std::vector<std::filesystem::path> detached_data_files(const std::filesystem::path& header);

}  // namespace ctsurg

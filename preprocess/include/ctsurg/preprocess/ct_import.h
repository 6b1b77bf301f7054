// CT import: any supported input (a DICOM series folder, NIfTI, NRRD with attached or detached
// data, MetaImage) to an HU volume in LPS mm with exact geometry.
#pragma once

#include "ctsurg/core/hu_volume_file.h"
#include "ctsurg/preprocess/detached_data_files.h"
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
  // Detached data files may lie outside their header's folder (image_file_reader.h).
  bool data_files_anywhere = false;
};

struct CtImport {
  HuVolume volume;
  std::vector<std::filesystem::path> files;  // every file the volume was read from (for provenance)
  std::vector<std::string> warnings;         // geometry and value warnings, with numbers
};

// Throws InputError naming the input for anything it cannot read, for a rescale that makes a value
// non-finite or beyond float range, and (RuntimeError) when the volume does not fit in memory.
CtImport import_ct(const std::filesystem::path& input, const CtImportOptions& options);

}  // namespace ctsurg

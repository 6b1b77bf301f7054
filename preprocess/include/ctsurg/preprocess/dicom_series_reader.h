// DICOM CT series from a folder: scan headers (GDCM), pick one series, read and rescale the slices
// (ITK's GDCMImageIO, which decodes every transfer syntax GDCM does, JPEG 2000 included).
//
// Rules (DICOM PS3.3 and the notes in ../shared/data/README.md):
//  - images are grouped by SeriesInstanceUID (0020,000E);
//  - localizers (ImageType contains LOCALIZER) and derived images (ImageType[0] == DERIVED) are
//    skipped, and so are files that are not images (DICOMDIR, reports);
//  - slices are ordered by ImagePositionPatient projected on the slice normal (slice_stack.h);
//  - HU = stored value x RescaleSlope + RescaleIntercept;
//  - gantry tilt (a sheared lattice) and uneven slice gaps are detected and reported with numbers.
#pragma once

#include "ctsurg/core/volume.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ctsurg {

struct DicomSeriesInfo {
  std::string series_uid;
  std::string series_number;
  std::string description;
  std::string modality;
  std::vector<std::filesystem::path> files;  // image files of this series (localizers/derived excluded)
};

// All image series under `folder` (recursively), ordered by series number then UID.
// `skipped` (optional) receives one line per skipped file and why.
// Throws InputError when the folder is missing or holds no DICOM image.
std::vector<DicomSeriesInfo> scan_dicom_folder(const std::filesystem::path& folder,
                                               std::vector<std::string>* skipped = nullptr);

// What to do when the slices are unevenly spaced.
enum class UnevenSlicePolicy {
  Resample,  // resample to even slices at the smallest gap (default: every voxel where it was scanned)
  Keep       // keep the acquired slices on a lattice with the mean step (dcm2niix's layout)
};

struct DicomReadOptions {
  std::string series;  // SeriesInstanceUID or SeriesNumber; empty: the folder must hold one series
  UnevenSlicePolicy uneven = UnevenSlicePolicy::Resample;
};

struct DicomVolume {
  Volume<float> hu;
  nlohmann::json source;                     // series UID, description, tilt, gaps, policy, ...
  std::vector<std::string> warnings;         // tilt and uneven spacing, with numbers
  std::vector<std::filesystem::path> files;  // slice files read, in slice order
};

// Reads one series as an HU volume in LPS mm. InputError (naming the folder or file and the DICOM
// field) for: no DICOM, several series and no `series` chosen, a series that does not exist, mixed
// orientations or sizes within the series, duplicate positions, undecodable pixel data, a volume
// too large for memory (checked before allocating).
DicomVolume read_dicom_series(const std::filesystem::path& folder, const DicomReadOptions& options);

}  // namespace ctsurg

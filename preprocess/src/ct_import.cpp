#include "ctsurg/preprocess/ct_import.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace ctsurg {

CtImport import_ct(const fs::path& input, const CtImportOptions& options) {
  CtImport out;
  if (!fs::exists(input)) throw InputError(input.string(), "", "does not exist");
  if (fs::is_directory(input)) {
    if (options.rescale_slope || options.rescale_intercept) {
      throw InputError(input.string(), "--rescale-slope/--rescale-intercept",
                       "DICOM carries its own RescaleSlope/RescaleIntercept; these options are for other formats");
    }
    DicomVolume d = read_dicom_series(input, options.dicom);
    out.volume.hu = std::move(d.hu);
    out.volume.source = std::move(d.source);
    out.files = std::move(d.files);
    out.warnings = std::move(d.warnings);
  } else {
    out.volume.hu = read_image_file(input, &out.warnings, {options.data_files_anywhere});
    const ImageFileFormat format = image_file_format(input);
    out.volume.source = {{"format", format == ImageFileFormat::Nifti  ? "nifti"
                                    : format == ImageFileFormat::Nrrd ? "nrrd"
                                                                      : "metaimage"},
                         {"file", input.filename().string()}};
    out.files.push_back(input);
    for (const auto& f : detached_data_files(input)) {
      if (fs::exists(f)) out.files.push_back(f);
    }
    if (options.rescale_slope || options.rescale_intercept) {
      const double slope = options.rescale_slope.value_or(1.0), intercept = options.rescale_intercept.value_or(0.0);
      if (!std::isfinite(slope) || slope == 0.0) throw InputError(input.string(), "--rescale-slope", "must be finite and non-zero");
      if (!std::isfinite(intercept)) throw InputError(input.string(), "--rescale-intercept", "must be finite");
      for (float& v : out.volume.hu.voxels) {
        const double hu = v * slope + intercept;
        // Beyond float range the volume would hold infinities; a CT spans a few thousand HU.
        if (!(std::abs(hu) <= 1e6)) {
          std::ostringstream m;
          m << "gives " << hu << " HU for the stored value " << v << " (slope " << slope << ", intercept " << intercept
            << "): outside +-1e6 HU, not a CT";
          throw InputError(input.string(), "--rescale-slope/--rescale-intercept", m.str());
        }
        v = static_cast<float>(hu);
      }
      out.volume.source["rescale"] = {{"slope", slope}, {"intercept", intercept}};
    }
  }
  const auto [lo, hi] = std::minmax_element(out.volume.hu.voxels.begin(), out.volume.hu.voxels.end());
  out.volume.source["hu_min"] = *lo;
  out.volume.source["hu_max"] = *hi;
  if (*lo >= 0.0f && *hi > 1500.0f) {
    std::ostringstream m;
    m << "values span [" << *lo << ", " << *hi
      << "] with no negative value: air should be about -1000 HU; are these raw stored values? "
         "(--rescale-intercept -1024 converts the usual offset)";
    out.warnings.push_back(m.str());
  }
  if (!out.volume.hu.geometry.is_orthonormal(1e-4) && out.volume.source.value("gantry_tilt_deg", 0.0) <= 0.01) {
    out.warnings.push_back("the direction matrix is not orthonormal (sheared lattice)");
  }
  return out;
}

}  // namespace ctsurg

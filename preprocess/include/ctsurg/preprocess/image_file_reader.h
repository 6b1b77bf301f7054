// Single-file medical images through ITK: NIfTI (.nii, .nii.gz), NRRD (.nrrd, .nhdr with detached
// data) and MetaImage (.mha, .mhd). Geometry comes out in LPS mm (ITK's convention; NIfTI's RAS is
// converted by ITK's NIfTI reader, which follows the standard's sform/qform rules).
//
// ITK is not trusted with damaged files: NIfTI and MetaImage files are verified first
// (nifti_verification.h, metaimage_verification.h), detached data files must lie beside their
// header, what ITK and the libraries under it print is captured and folded into the error (or a
// warning), and ITK's result is checked again: sane geometry (ImageGeometry::validate), the voxel
// count of the header, finite values. Messages name the user's file, never a temporary copy.
#pragma once

#include "ctsurg/core/volume.h"

#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

enum class ImageFileFormat { Nifti, Nrrd, MetaImage };

// Format by file name suffix, or InputError naming the file when it is none of the above.
ImageFileFormat image_file_format(const std::filesystem::path& path);

struct ImageReadOptions {
  // Detached data files (MetaImage ElementDataFile, NRRD "data file") may lie outside the header's
  // folder (ctsurg-import --allow-data-outside). Off: a header cannot make ctsurg read any file.
  bool data_files_anywhere = false;
};

struct ImageFileInfo {
  ImageGeometry geometry;
  std::string component_type;  // stored voxel type as ITK names it: "short", "float", "unsigned_char", ...
  int components = 1;
};

// Reads only the header. InputError for a missing, unreadable or malformed file (message names the
// file and the field), for non-scalar or non-3D images, and for absurd geometry. Recoverable header
// defects are repaired and reported in `warnings` (optional): a detached NRRD header that gives
// "spacings" together with "space" (the NRRD format allows only "space directions" then) is read
// as axis-aligned with those spacings.
ImageFileInfo read_image_file_info(const std::filesystem::path& path, std::vector<std::string>* warnings = nullptr,
                                   const ImageReadOptions& options = {});

// Reads the whole image as float (values after the file's own scaling, e.g. NIfTI scl_slope/inter).
// Checks the allocation against available memory before reading, and rejects NaN or infinite
// values (InputError naming the first bad voxel).
Volume<float> read_image_file(const std::filesystem::path& path, std::vector<std::string>* warnings = nullptr,
                              const ImageReadOptions& options = {});

}  // namespace ctsurg

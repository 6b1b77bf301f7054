// What ctsurg verifies in a NIfTI file (.nii, .nii.gz; NIfTI-1 and NIfTI-2, either byte order)
// before ITK reads it. ITK's NIfTI library repairs or ignores what it cannot use (a short file
// reads as zeros, NaN voxels as 0, a pixdim of 0 or NaN as 1 mm, a broken magic as Analyze 7.5, a
// bad gzip CRC is never checked), so a damaged file would import as a different image. Here
// every such defect is refused with the field that has it (NIfTI-1 standard, nifti1.h; NIfTI-2,
// nifti2.h):
//  - the header: sizeof_hdr 348 or 540, magic "n+1"/"n+2" (a single file; an Analyze or a
//    .hdr/.img header is refused), dim[0] in 1..7 with positive dims and nothing beyond one 3D
//    volume, a datatype ctsurg reads (integers and reals, not complex or RGB) with the matching
//    bitpix, pixdim[1..3] finite and positive, pixdim[0] (qfac) -1, 0 or 1, finite scl_slope and
//    scl_inter, qform/sform codes 0..5, finite quaternion and offsets (b^2 + c^2 + d^2 <= 1) when
//    qform_code > 0, a finite, non-singular sform with sane spacing and offsets when
//    sform_code > 0;
//  - the layout: vox_offset a whole number past the header (and past every extension, whose sizes
//    are positive multiples of 16), the voxel data complete (a file cut short is refused; bytes
//    after it are reported);
//  - the compression (.nii.gz): every gzip member's CRC-32 and length (zlib checks them at the
//    end of each member, so the whole file is decompressed once);
//  - the values: float32/float64 voxels are all finite.
// A sheared or unnormalised geometry is then checked by ImageGeometry::validate on ITK's result.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

// InputError(path, field, problem) for the first defect found; what is legal but unusual (no
// orientation codes, bytes after the data) goes to `warnings`.
void verify_nifti_file(const std::filesystem::path& path, std::vector<std::string>* warnings = nullptr);

}  // namespace ctsurg

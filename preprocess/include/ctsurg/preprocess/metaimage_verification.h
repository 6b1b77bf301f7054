// What ctsurg verifies in a MetaImage file (.mha with its data inside, .mhd with data files beside
// it) before ITK reads it. ITK's MetaImage reader ignores its own read errors (a short data file, a
// damaged compressed stream) and follows ElementDataFile anywhere on the disk; a corrupt header
// could overflow the voxel count or make it parse a million dimensions. Here:
//  - the header: at most 1 MiB of "Key = Value" lines ending with ElementDataFile; NDims 2..4;
//    DimSize NDims positive whole numbers whose product (times the element size) does not
//    overflow and holds one 3D volume (a 4th dimension of 1); ElementType one of MET_CHAR ..
//    MET_DOUBLE; one channel; BinaryData True (ASCII data is refused); HeaderSize a whole number
//    or -1;
//  - the data files: LOCAL (after the header), one file, a printf pattern with min max step, or a
//    LIST; each a regular file inside the header's folder (no absolute path, no "..", no link
//    leading out) unless `data_files_anywhere` (ctsurg-import --allow-data-outside);
//  - the data: uncompressed, the files hold at least the header's bytes (more is reported);
//    compressed (CompressedData True, one stream), the zlib/gzip stream decompresses without error,
//    ends, and gives exactly the header's bytes, and CompressedDataSize, when given, is the size
//    of that stream.
// Non-finite voxels and the geometry are checked on ITK's result (image_file_reader.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace ctsurg {

// InputError(path, field, problem) for the first defect found; returns the data files (empty for
// LOCAL data). Warnings (bytes beyond the data) go to `warnings`.
std::vector<std::filesystem::path> verify_metaimage_file(const std::filesystem::path& path, bool data_files_anywhere,
                                                         std::vector<std::string>* warnings = nullptr);

// InputError(header, field, ...) unless `data_file` (as named in the header, relative to its folder)
// lies inside the header's folder: not absolute, no "..", no symbolic link leading out.
void check_data_file_beside_header(const std::filesystem::path& header, const std::filesystem::path& data_file,
                                   const std::string& field);

}  // namespace ctsurg

// Hand-made NIfTI-1 files (the standard's 348-byte header, little endian) for tests: every header
// field can be set to a broken value without going through ITK, and the file written plain or
// gzip-compressed.
#pragma once

#include <zlib.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace ctsurg::test {

struct NiftiSpec {
  std::array<int16_t, 8> dim{3, 4, 3, 2, 1, 1, 1, 1};
  int16_t datatype = 16, bitpix = 32;  // float32
  std::array<float, 8> pixdim{1, 1.5f, 1.5f, 2, 0, 0, 0, 0};
  float vox_offset = 352, scl_slope = 0, scl_inter = 0;
  int16_t qform_code = 0, sform_code = 1;
  std::array<float, 6> quatern{0, 0, 0, 0, 0, 0};  // b, c, d, qoffset x, y, z
  std::array<float, 12> srow{-1.5f, 0, 0, 10, 0, -1.5f, 0, 20, 0, 0, 2, 30};  // RAS mm
  std::string magic{"n+1\0", 4};
  std::vector<float> values;  // dim[1] x dim[2] x dim[3] float32 values (default: 0, 1, 2, ...)
};

inline std::string nifti_bytes(const NiftiSpec& s) {
  std::string h(348, '\0');
  const auto put = [&](std::size_t offset, const auto& v) { std::memcpy(h.data() + offset, &v, sizeof v); };
  put(0, int32_t{348});
  for (int i = 0; i < 8; ++i) put(40 + 2 * i, s.dim[i]);
  put(70, s.datatype);
  put(72, s.bitpix);
  for (int i = 0; i < 8; ++i) put(76 + 4 * i, s.pixdim[i]);
  put(108, s.vox_offset);
  put(112, s.scl_slope);
  put(116, s.scl_inter);
  put(123, static_cast<char>(2 | 8));  // mm, s
  put(252, s.qform_code);
  put(254, s.sform_code);
  for (int i = 0; i < 6; ++i) put(256 + 4 * i, s.quatern[i]);
  for (int i = 0; i < 12; ++i) put(280 + 4 * i, s.srow[i]);
  std::memcpy(h.data() + 344, s.magic.data(), 4);
  std::string out = h + std::string(4, '\0');  // no extensions
  const std::size_t offset = static_cast<std::size_t>(s.vox_offset);
  if (offset > out.size() && offset < (1u << 20)) out.resize(offset, '\0');
  std::vector<float> values = s.values;
  if (values.empty()) {
    values.resize(static_cast<std::size_t>(s.dim[1]) * s.dim[2] * s.dim[3]);
    for (std::size_t n = 0; n < values.size(); ++n) values[n] = static_cast<float>(n);
  }
  out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  return out;
}

// Writes `bytes` to `path`, gzip-compressed when the name ends in .gz.
inline void write_nifti_bytes(const std::filesystem::path& path, const std::string& bytes) {
  if (path.extension() == ".gz") {
    gzFile f = gzopen(path.c_str(), "wb6");
    gzwrite(f, bytes.data(), static_cast<unsigned>(bytes.size()));
    gzclose(f);
  } else {
    std::ofstream(path, std::ios::binary) << bytes;
  }
}

inline std::filesystem::path write_nifti(const std::filesystem::path& path, const NiftiSpec& spec) {
  write_nifti_bytes(path, nifti_bytes(spec));
  return path;
}

}  // namespace ctsurg::test

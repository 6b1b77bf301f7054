// An independent reading of a NIfTI-1 header (zlib + the standard's byte layout), used as a peer to
// check the geometry that ITK gives ctsurg: world RAS = srow * (i, j, k, 1) when sform_code > 0.
#pragma once

#include <zlib.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace ctsurg::test {

struct NiftiPeerHeader {
  std::array<int, 3> dims{};
  std::array<float, 3> pixdim{};
  int qform_code = 0, sform_code = 0;
  std::array<std::array<double, 4>, 3> srow{};  // RAS mm

  // LPS mm of voxel (i, j, k) from the sform.
  std::array<double, 3> lps(double i, double j, double k) const {
    std::array<double, 3> ras{};
    for (int r = 0; r < 3; ++r) ras[r] = srow[r][0] * i + srow[r][1] * j + srow[r][2] * k + srow[r][3];
    return {-ras[0], -ras[1], ras[2]};
  }
};

inline NiftiPeerHeader read_nifti_peer_header(const std::filesystem::path& path) {
  gzFile f = gzopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + path.string());
  unsigned char h[348];
  const int got = gzread(f, h, sizeof h);
  gzclose(f);
  if (got != 348) throw std::runtime_error("short NIfTI header");
  const auto i16 = [&](int off) { int16_t v; std::memcpy(&v, h + off, 2); return v; };
  const auto f32 = [&](int off) { float v; std::memcpy(&v, h + off, 4); return v; };
  NiftiPeerHeader p;
  for (int a = 0; a < 3; ++a) {
    p.dims[a] = i16(42 + 2 * a);
    p.pixdim[a] = f32(80 + 4 * a);
  }
  p.qform_code = i16(252);
  p.sform_code = i16(254);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) p.srow[r][c] = f32(280 + 16 * r + 4 * c);
  return p;
}

}  // namespace ctsurg::test

#include "ctsurg/preprocess/nifti_verification.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/input_file.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <sstream>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

// The decompressed bytes of a .nii.gz (or the bytes of a .nii: zlib reads plain files as they are),
// with every gzip member's CRC-32 and length checked by zlib when the member ends.
class ByteStream {
 public:
  ByteStream(const fs::path& path, std::string name) : name_(std::move(name)), f_(gzopen(path.c_str(), "rb")) {
    if (!f_) throw InputError(name_, "", "cannot be opened");
    gzbuffer(f_, 1 << 17);
  }
  ~ByteStream() { gzclose(f_); }
  ByteStream(const ByteStream&) = delete;
  ByteStream& operator=(const ByteStream&) = delete;

  // Reads up to `n` bytes; fewer only at the end of the data. InputError on a gzip error.
  std::size_t read(void* out, std::size_t n) {
    std::size_t done = 0;
    while (done < n) {
      const unsigned ask = static_cast<unsigned>(std::min<std::size_t>(n - done, 1 << 20));
      const int got = gzread(f_, static_cast<char*>(out) + done, ask);
      if (got < 0) fail();
      if (got == 0) break;
      done += static_cast<std::size_t>(got);
    }
    if (done < n) check_end();
    position_ += done;
    return done;
  }
  // Skips `n` bytes; returns how many there were.
  uint64_t skip(uint64_t n) {
    std::array<char, 1 << 16> buffer;
    uint64_t done = 0;
    while (done < n) {
      const std::size_t got = read(buffer.data(), static_cast<std::size_t>(std::min<uint64_t>(n - done, buffer.size())));
      done += got;
      if (got == 0) break;
    }
    return done;
  }
  uint64_t position() const { return position_; }
  bool compressed() const { return gzdirect(f_) == 0; }

 private:
  [[noreturn]] void fail() const {
    int code = Z_OK;
    const char* text = gzerror(f_, &code);
    throw InputError(name_, "gzip", std::string("the compressed data are damaged: ") + (text ? text : "zlib error") +
                                         " (a flipped bit or a cut file; the gzip CRC-32 and length must match)");
  }
  // zlib reports a cut or damaged member at the end of the stream, not as a short read.
  void check_end() const {
    int code = Z_OK;
    gzerror(f_, &code);
    if (code != Z_OK && code != Z_STREAM_END) fail();
  }
  std::string name_;
  gzFile f_;
  uint64_t position_ = 0;
};

// A header read in its file's byte order.
class Fields {
 public:
  Fields(const unsigned char* bytes, bool swap) : b_(bytes), swap_(swap) {}
  template <class T>
  T get(std::size_t offset) const {
    std::array<unsigned char, sizeof(T)> raw;
    std::memcpy(raw.data(), b_ + offset, sizeof(T));
    if (swap_) std::reverse(raw.begin(), raw.end());
    T v;
    std::memcpy(&v, raw.data(), sizeof(T));
    return v;
  }

 private:
  const unsigned char* b_;
  bool swap_;
};

// The fields ctsurg checks, the same for both versions of the format.
struct NiftiHeader {
  int version = 1;                    // 1 or 2
  std::size_t size = 348;             // sizeof_hdr
  bool swap = false;
  std::array<int64_t, 8> dim{};
  int datatype = 0, bitpix = 0;
  std::array<double, 8> pixdim{};
  double vox_offset = 0, scl_slope = 0, scl_inter = 0;
  int qform_code = 0, sform_code = 0;
  std::array<double, 6> quatern{};    // b, c, d, qoffset x, y, z
  std::array<double, 12> srow{};      // srow_x, srow_y, srow_z
  std::string magic;
};

uint32_t raw_u32(const unsigned char* b) {
  uint32_t v;
  std::memcpy(&v, b, 4);
  return v;
}

uint32_t byte_swap(uint32_t v) { return __builtin_bswap32(v); }

// Where the fields lie in each version's header (nifti1.h, nifti2.h).
struct Offsets {
  std::size_t magic, magic_size, dim, datatype, bitpix, pixdim, vox_offset, scl_slope, scl_inter, qform_code, sform_code,
      quatern, srow;
};
constexpr Offsets kNifti1{344, 4, 40, 70, 72, 76, 108, 112, 116, 252, 254, 256, 280};
constexpr Offsets kNifti2{4, 8, 16, 12, 14, 104, 168, 176, 184, 344, 348, 352, 400};

// The fields at `o`, stored as Dim (dim), Code (the xform codes), Real (pixdim, scaling, qform,
// srow) and Offset (vox_offset): NIfTI-1 int16/int16/float32/float32, NIfTI-2 int64/int32/float64/int64.
template <class Dim, class Code, class Real, class Offset>
void read_fields(const Fields& f, const unsigned char* h, const Offsets& o, NiftiHeader& hd) {
  hd.magic.assign(reinterpret_cast<const char*>(h + o.magic), o.magic_size);
  for (std::size_t i = 0; i < 8; ++i) hd.dim[i] = f.get<Dim>(o.dim + sizeof(Dim) * i);
  hd.datatype = f.get<int16_t>(o.datatype);
  hd.bitpix = f.get<int16_t>(o.bitpix);
  for (std::size_t i = 0; i < 8; ++i) hd.pixdim[i] = f.get<Real>(o.pixdim + sizeof(Real) * i);
  hd.vox_offset = static_cast<double>(f.get<Offset>(o.vox_offset));
  hd.scl_slope = f.get<Real>(o.scl_slope);
  hd.scl_inter = f.get<Real>(o.scl_inter);
  hd.qform_code = f.get<Code>(o.qform_code);
  hd.sform_code = f.get<Code>(o.sform_code);
  for (std::size_t i = 0; i < 6; ++i) hd.quatern[i] = f.get<Real>(o.quatern + sizeof(Real) * i);
  for (std::size_t i = 0; i < 12; ++i) hd.srow[i] = f.get<Real>(o.srow + sizeof(Real) * i);
}

NiftiHeader parse_header(const unsigned char* h, std::size_t size, bool swap) {
  const Fields f(h, swap);
  NiftiHeader hd;
  hd.size = size;
  hd.swap = swap;
  hd.version = size == 348 ? 1 : 2;
  if (hd.version == 1) {
    read_fields<int16_t, int16_t, float, float>(f, h, kNifti1, hd);
  } else {
    read_fields<int64_t, int32_t, double, int64_t>(f, h, kNifti2, hd);
  }
  return hd;
}

// Bytes per voxel of the datatypes ctsurg reads (nifti1.h DT_*), 0 for any other.
int datatype_bytes(int datatype) {
  switch (datatype) {
    case 2: case 256: return 1;      // uint8, int8
    case 4: case 512: return 2;      // int16, uint16
    case 8: case 768: case 16: return 4;  // int32, uint32, float32
    case 64: case 1024: case 1280: return 8;  // float64, int64, uint64
    default: return 0;
  }
}

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void check_header(const NiftiHeader& h, const std::string& name, std::vector<std::string>* warnings) {
  const auto fail = [&](const std::string& field, const std::string& problem) { throw InputError(name, field, problem); };
  const std::string want = h.version == 1 ? std::string("n+1\0", 4) : std::string("n+2\0\r\n\032\n", 8);
  if (h.magic != want) {
    if (h.version == 1 && h.magic == std::string("ni1\0", 4)) {
      fail("magic", "'ni1' is the header of a .hdr/.img pair; ctsurg reads single-file NIfTI (.nii, .nii.gz)");
    }
    fail("magic", std::string("is not 'n+") + (h.version == 1 ? "1" : "2") +
                      "': an Analyze 7.5 file or a corrupt header (its orientation would be guessed)");
  }
  if (h.dim[0] < 1 || h.dim[0] > 7) fail("dim[0]", "must be 1..7 (the number of dimensions), got " + std::to_string(h.dim[0]));
  int64_t voxels = 1;
  for (int i = 1; i <= h.dim[0]; ++i) {
    if (h.dim[i] < 1) fail("dim[" + std::to_string(i) + "]", "must be at least 1, got " + std::to_string(h.dim[i]));
    if (i > 3 && h.dim[i] != 1) {
      fail("dim[" + std::to_string(i) + "]", "is " + std::to_string(h.dim[i]) + ": ctsurg reads one 3D volume");
    }
    if (__builtin_mul_overflow(voxels, h.dim[i], &voxels) || voxels > ImageGeometry::kMaxVoxels) {
      fail("dim", "more than 2^48 voxels: not an image");
    }
  }
  const int bytes = datatype_bytes(h.datatype);
  if (bytes == 0) {
    fail("datatype", std::to_string(h.datatype) + " is not a scalar integer or real type (complex, RGB and float128 "
                     "are not CT values)");
  }
  if (h.bitpix != 8 * bytes) {
    fail("bitpix", "is " + std::to_string(h.bitpix) + ", but datatype " + std::to_string(h.datatype) + " has " +
                       std::to_string(8 * bytes) + " bits");
  }
  for (int i = 1; i <= std::min<int64_t>(3, h.dim[0]); ++i) {
    if (!std::isfinite(h.pixdim[i]) || h.pixdim[i] <= 0) {
      fail("pixdim[" + std::to_string(i) + "]", "voxel size must be a positive number of mm, got " + number(h.pixdim[i]));
    }
  }
  if (!(h.pixdim[0] == 1 || h.pixdim[0] == -1 || h.pixdim[0] == 0)) {
    fail("pixdim[0]", "qfac must be -1 or 1 (0 is read as 1), got " + number(h.pixdim[0]));
  }
  if (!std::isfinite(h.scl_slope) || (h.scl_slope != 0 && !std::isfinite(h.scl_inter))) {
    fail("scl_slope/scl_inter", "the value scaling must be finite, got slope " + number(h.scl_slope) + ", intercept " +
                                    number(h.scl_inter));
  }
  for (const auto& [code, field] : {std::pair{h.qform_code, "qform_code"}, std::pair{h.sform_code, "sform_code"}}) {
    if (code < 0 || code > 5) fail(field, "must be 0..5, got " + std::to_string(code));
  }
  const auto bounded = [](double v, double limit) { return std::isfinite(v) && std::abs(v) <= limit; };
  if (h.qform_code > 0) {
    for (int i = 0; i < 6; ++i) {
      if (!bounded(h.quatern[i], i < 3 ? 1.0 + 1e-6 : ImageGeometry::kMaxCoordinateMm)) {
        fail(i < 3 ? "quatern_b/c/d" : "qoffset_x/y/z",
             "must be finite" + std::string(i < 3 ? " and at most 1" : " and within 1e7 mm") + " (qform_code " +
                 std::to_string(h.qform_code) + "), got " + number(h.quatern[i]));
      }
    }
    const double b = h.quatern[0], c = h.quatern[1], d = h.quatern[2];
    if (b * b + c * c + d * d > 1.0 + 1e-5) fail("quatern_b/c/d", "b^2 + c^2 + d^2 is more than 1: not a rotation");
  }
  if (h.sform_code > 0) {
    double det = 0;
    std::array<double, 3> lengths{};
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 3; ++r) {
        const double v = h.srow[static_cast<std::size_t>(4 * r + c)];
        const double limit = c < 3 ? ImageGeometry::kMaxSpacingMm : ImageGeometry::kMaxCoordinateMm;
        if (!bounded(v, limit)) {
          fail(std::string("srow_") + "xyz"[r], "must be finite and within " + number(limit) + " mm (sform_code " +
                                                    std::to_string(h.sform_code) + "), got " + number(v));
        }
        if (c < 3) lengths[static_cast<std::size_t>(c)] += v * v;
      }
    }
    const auto m = [&](int r, int c) { return h.srow[static_cast<std::size_t>(4 * r + c)]; };
    det = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0)) +
          m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
    const double scale = std::sqrt(lengths[0] * lengths[1] * lengths[2]);
    if (!(scale > 0) || std::abs(det) < 1e-6 * scale) fail("srow_x/y/z", "the sform's 3x3 part is singular");
  }
  if (h.qform_code == 0 && h.sform_code == 0 && warnings) {
    warnings->push_back("qform_code and sform_code are both 0: the file gives no orientation; read with the voxel sizes "
                        "and an identity orientation at the origin (NIfTI method 1)");
  }
  if (!std::isfinite(h.vox_offset) || h.vox_offset != std::floor(h.vox_offset) ||
      h.vox_offset < static_cast<double>(h.size + 4) || h.vox_offset > 1e15) {
    fail("vox_offset", "must be a whole number of bytes, at least " + std::to_string(h.size + 4) +
                           " (after the header and its extension flag), got " + number(h.vox_offset));
  }
}

// Walks the extensions (NIfTI-1 standard, "extension" section): each esize a positive multiple of
// 16, the chain ending at or before vox_offset.
void check_extensions(ByteStream& in, const std::array<unsigned char, 4>& extender, const NiftiHeader& h, uint64_t vox_offset,
                      const std::string& name) {
  if (extender[0] == 0) return;
  while (in.position() + 8 <= vox_offset) {
    std::array<unsigned char, 8> e{};
    if (in.read(e.data(), 8) != 8) throw InputError(name, "extension", "the file ends inside an extension");
    uint32_t esize = raw_u32(e.data());
    if (h.swap) esize = byte_swap(esize);
    if (esize < 16 || esize % 16 != 0 || in.position() - 8 + esize > vox_offset) {
      throw InputError(name, "extension", "esize " + std::to_string(static_cast<int32_t>(esize)) +
                                              " is not a positive multiple of 16 ending before vox_offset");
    }
    if (in.skip(esize - 8) != esize - 8) throw InputError(name, "extension", "the file ends inside an extension");
    if (in.position() + 8 > vox_offset) break;
  }
}

// The first non-finite value of a float32/float64 buffer (in file byte order), or -1.
int64_t first_non_finite(const unsigned char* data, std::size_t count, int bytes, bool swap) {
  for (std::size_t n = 0; n < count; ++n) {
    std::array<unsigned char, 8> raw{};
    std::memcpy(raw.data(), data + n * static_cast<std::size_t>(bytes), static_cast<std::size_t>(bytes));
    if (swap) std::reverse(raw.begin(), raw.begin() + bytes);
    bool finite;
    if (bytes == 4) {
      float v;
      std::memcpy(&v, raw.data(), 4);
      finite = std::isfinite(v);
    } else {
      double v;
      std::memcpy(&v, raw.data(), 8);
      finite = std::isfinite(v);
    }
    if (!finite) return static_cast<int64_t>(n);
  }
  return -1;
}

}  // namespace

void verify_nifti_file(const fs::path& path, std::vector<std::string>* warnings) {
  const std::string name = path.string();
  check_input_file(path);
  ByteStream in(path, name);
  std::array<unsigned char, 540> head{};
  if (in.read(head.data(), 4) != 4) throw InputError(name, "header", "the file is shorter than a NIfTI header");
  const uint32_t sizeof_hdr = raw_u32(head.data());
  bool swap = false;
  std::size_t size = 0;
  for (const uint32_t s : {348u, 540u}) {
    if (sizeof_hdr == s) size = s;
    if (byte_swap(sizeof_hdr) == s) size = s, swap = true;
  }
  if (size == 0) {
    throw InputError(name, "sizeof_hdr", "is " + std::to_string(static_cast<int32_t>(sizeof_hdr)) +
                                             ", not 348 (NIfTI-1) or 540 (NIfTI-2): not a NIfTI file");
  }
  if (in.read(head.data() + 4, size - 4) != size - 4) {
    throw InputError(name, "header", "the file ends inside the " + std::to_string(size) + "-byte header");
  }
  const NiftiHeader h = parse_header(head.data(), size, swap);
  check_header(h, name, warnings);
  std::array<unsigned char, 4> extender{};
  if (in.read(extender.data(), 4) != 4) throw InputError(name, "extension", "the file ends after the header");
  const uint64_t vox_offset = static_cast<uint64_t>(h.vox_offset);
  check_extensions(in, extender, h, vox_offset, name);
  const uint64_t gap = vox_offset - in.position();
  if (in.skip(gap) != gap) {
    throw InputError(name, "vox_offset", "is " + std::to_string(vox_offset) + ", past the end of the file");
  }

  int64_t voxels = 1;
  for (int i = 1; i <= h.dim[0]; ++i) voxels *= h.dim[i];
  const int bytes = h.bitpix / 8;
  const bool real = h.datatype == 16 || h.datatype == 64;
  const uint64_t expected = static_cast<uint64_t>(voxels) * static_cast<uint64_t>(bytes);
  std::vector<unsigned char> buffer(static_cast<std::size_t>(bytes) << 18);
  uint64_t got = 0;
  while (got < expected) {
    const std::size_t want = static_cast<std::size_t>(std::min<uint64_t>(expected - got, buffer.size()));
    const std::size_t n = in.read(buffer.data(), want);
    if (real && n > 0) {
      const int64_t bad = first_non_finite(buffer.data(), n / static_cast<std::size_t>(bytes), bytes, h.swap);
      if (bad >= 0) {
        const int64_t v = static_cast<int64_t>(got / static_cast<uint64_t>(bytes)) + bad;
        const int64_t nx = h.dim[1], ny = h.dim[0] >= 2 ? h.dim[2] : 1;
        throw InputError(name, "voxel data",
                         "non-finite value (NaN or infinity) at voxel (" + std::to_string(v % nx) + ", " +
                             std::to_string(v / nx % ny) + ", " + std::to_string(v / (nx * ny)) + ")");
      }
    }
    got += n;
    if (n < want) break;
  }
  if (got < expected) {
    throw InputError(name, "voxel data",
                     "the file is cut short: the header needs " + std::to_string(expected) + " bytes of voxel data after "
                     "vox_offset " + std::to_string(vox_offset) + ", the file has " + std::to_string(got) +
                         (in.compressed() ? " (after decompression)" : ""));
  }
  const uint64_t trailing = in.skip(UINT64_MAX);
  if (trailing > 0 && warnings) {
    warnings->push_back(std::to_string(trailing) + " bytes after the voxel data are not part of the image (ignored)");
  }
}

}  // namespace ctsurg

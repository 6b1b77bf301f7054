#include "ctsurg/preprocess/dicom_file_check.h"

#include "ctsurg/core/error.h"

#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

constexpr uint32_t kUndefined = 0xffffffffu;
constexpr int kMaxDepth = 64;

class Walker {
 public:
  Walker(const fs::path& file, uint64_t size) : in_(file, std::ios::binary), name_(file.string()), size_(size) {}

  // The file meta group (always explicit VR little endian); returns the transfer syntax UID.
  std::string meta() {
    std::string syntax;
    while (at_ + 6 <= size_) {
      const uint64_t start = at_;
      const uint16_t group = u16();
      if (group != 0x0002) {
        seek(start);
        break;
      }
      const uint16_t element = u16();
      const uint32_t length = value_length(group, element, true);
      if (element == 0x0010 && length < 256) {
        syntax = bytes(length);
        while (!syntax.empty() && (syntax.back() == '\0' || syntax.back() == ' ')) syntax.pop_back();
      } else {
        skip(group, element, length);
      }
    }
    return syntax;
  }

  // Elements until the end of the file, or of the enclosing item or sequence.
  void dataset(bool is_explicit, bool big_endian, int depth) {
    explicit_ = is_explicit;
    big_endian_ = big_endian;
    if (depth > kMaxDepth) throw InputError(name_, "sequence", "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    while (at_ + 8 <= size_) {
      const uint16_t group = u16(), element = u16();
      if (group == 0xfffe) {  // item (E000), item delimiter (E00D), sequence delimiter (E0DD)
        const uint32_t length = u32();
        if (element == 0xe00d || element == 0xe0dd) return;
        if (length == kUndefined) {
          dataset(explicit_, big_endian_, depth + 1);
        } else {
          skip(group, element, length);
        }
        continue;
      }
      const uint32_t length = value_length(group, element, explicit_);
      if (length == kUndefined) {
        items(depth + 1);  // a sequence, or encapsulated pixel data, of undefined length
      } else {
        skip(group, element, length);
      }
    }
  }

 private:
  // Items (each defined-length, or of undefined length down to its delimiter) until the sequence
  // delimiter.
  void items(int depth) {
    if (depth > kMaxDepth) throw InputError(name_, "sequence", "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    while (at_ + 8 <= size_) {
      const uint16_t group = u16(), element = u16();
      const uint32_t length = u32();
      if (group != 0xfffe) throw InputError(name_, tag(group, element), "expected an item inside a sequence");
      if (element == 0xe0dd) return;
      if (length == kUndefined) {
        dataset(explicit_, big_endian_, depth + 1);
      } else {
        skip(group, element, length);
      }
    }
  }

  uint32_t value_length(uint16_t group, uint16_t element, bool is_explicit) {
    if (!is_explicit) return u32();
    const std::string vr = bytes(2);
    // A VR that is none of the standard's makes GDCM fall back to reading the element as implicit
    // VR (another length field), where its own assertions abort on damaged files.
    static const std::string known = "AE AS AT CS DA DS DT FD FL IS LO LT OB OD OF OL OV OW PN SH SL SQ SS ST SV TM UC UI UL UN UR US UT UV";
    if (vr.find(' ') != std::string::npos || known.find(vr) == std::string::npos || known.find(vr) % 3 != 0) {
      throw InputError(name_, tag(group, element), "'" + printable(vr) + "' is not a DICOM value representation (PS3.5 6.2)");
    }
    static const std::array<const char*, 13> long_form{"OB", "OD", "OF", "OL", "OV", "OW", "SQ", "SV", "UC", "UN", "UR", "UT", "UV"};
    for (const char* v : long_form) {
      if (vr == v) {
        skip(group, element, 2);  // reserved
        return u32();
      }
    }
    return u16();
  }

  void skip(uint16_t group, uint16_t element, uint64_t length) {
    if (length > size_ - at_) {
      throw InputError(name_, tag(group, element),
                       "declares " + std::to_string(length) + " bytes, but the file has " + std::to_string(size_ - at_) +
                           " left (a corrupt length)");
    }
    seek(at_ + length);
  }

  std::string bytes(uint64_t n) {
    if (n > size_ - at_) throw InputError(name_, "header", "the file ends inside an element");
    std::string s(static_cast<std::size_t>(n), '\0');
    in_.read(s.data(), static_cast<std::streamsize>(n));
    at_ += n;
    return s;
  }
  uint16_t u16() {
    const std::string b = bytes(2);
    const auto lo = static_cast<uint8_t>(b[big_endian_ ? 1 : 0]), hi = static_cast<uint8_t>(b[big_endian_ ? 0 : 1]);
    return static_cast<uint16_t>(lo | hi << 8);
  }
  uint32_t u32() {
    const uint32_t a = u16(), b = u16();
    return big_endian_ ? (a << 16 | b) : (a | b << 16);
  }
  void seek(uint64_t to) {
    at_ = to;
    in_.seekg(static_cast<std::streamoff>(to));
  }
  static std::string printable(const std::string& s) {
    std::string out;
    for (const char c : s) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(c));
      out += c >= 0x20 && c < 0x7f ? std::string(1, c) : std::string(hex);
    }
    return out;
  }
  static std::string tag(uint16_t group, uint16_t element) {
    char text[16];
    std::snprintf(text, sizeof text, "(%04X,%04X)", group, element);
    return text;
  }

  std::ifstream in_;
  std::string name_;
  uint64_t size_, at_ = 0;
  bool explicit_ = true, big_endian_ = false;
  friend void ctsurg::check_dicom_element_lengths(const fs::path&);
};

}  // namespace

void check_dicom_element_lengths(const fs::path& file) {
  std::error_code ec;
  const uint64_t size = fs::file_size(file, ec);
  if (ec || size < 132) return;
  Walker w(file, size);
  w.seek(128);
  if (w.bytes(4) != "DICM") return;
  const std::string syntax = w.meta();
  if (syntax == "1.2.840.10008.1.2.1.99") return;  // deflated: GDCM inflates it first
  w.dataset(syntax != "1.2.840.10008.1.2", syntax == "1.2.840.10008.1.2.2", 0);
}

}  // namespace ctsurg

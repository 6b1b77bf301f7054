#include "ctsurg/preprocess/metaimage_verification.h"

#include "ctsurg/core/error.h"
#include "ctsurg/core/image_geometry.h"
#include "ctsurg/core/input_file.h"
#include "ctsurg/preprocess/detached_data_files.h"
#include "header_text.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 20;
constexpr std::size_t kMaxMetaIOString = 255;       // MET_MAX_NAME_SIZE and MetaObject's char[255] fields
constexpr std::size_t kMaxMetaIOFieldBytes = 4096;  // MET_MAX_NUMBER_OF_FIELD_VALUES: MET_Read's limit of a string value

// Bytes of each MetaIO element type (metaTypes.h, MET_ValueTypeSize).
const std::map<std::string, int>& element_sizes() {
  static const std::map<std::string, int> sizes{
      {"MET_CHAR", 1},      {"MET_UCHAR", 1},      {"MET_SHORT", 2}, {"MET_USHORT", 2},
      {"MET_INT", 4},       {"MET_UINT", 4},       {"MET_LONG", 4},  {"MET_ULONG", 4},
      {"MET_LONG_LONG", 8}, {"MET_ULONG_LONG", 8}, {"MET_FLOAT", 4}, {"MET_DOUBLE", 8}};
  return sizes;
}

bool is_true(const std::string& v) {
  std::string l = v;
  std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return l == "true" || l == "1";
}

int64_t whole_number(const std::string& text, const std::string& name, const std::string& field, int64_t lo, int64_t hi) {
  std::size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || trim_header_text(text.substr(used)) != "" || v < lo || v > hi) {
    throw InputError(name, field, "'" + text + "' is not a whole number in [" + std::to_string(lo) + ", " +
                                      std::to_string(hi) + "]");
  }
  return v;
}

struct MetaImageHeader {
  std::map<std::string, std::string> fields;  // key -> value, as written
  uint64_t data_start = 0;                    // LOCAL: the byte after the ElementDataFile line
};

MetaImageHeader read_header(const fs::path& path, const std::string& name) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(name, "", "cannot be opened");
  MetaImageHeader h;
  std::string line;
  uint64_t position = 0;
  while (true) {
    if (position > kMaxHeaderBytes) throw InputError(name, "ElementDataFile", "missing in the first 1 MiB: not a MetaImage header");
    if (!std::getline(in, line)) throw InputError(name, "ElementDataFile", "missing: the header must end with it");
    position += line.size() + 1;
    if (line.find('\0') != std::string::npos) throw InputError(name, "header", "binary bytes before ElementDataFile: not a MetaImage header");
    const auto eq = line.find('=');
    if (eq == std::string::npos) {
      if (trim_header_text(line).empty()) continue;
      throw InputError(name, "header", "line '" + trim_header_text(line).substr(0, 60) + "' is not 'Key = Value'");
    }
    const std::string key = trim_header_text(line.substr(0, eq)), value = trim_header_text(line.substr(eq + 1));
    // MetaIO (ITK 5.2) copies keys and string values into 255-byte buffers with strcpy
    // (metaTypes.h MET_MAX_NAME_SIZE; metaObject.h m_ObjectTypeName, m_Comment, m_Name ...): longer ones
    // overflow them, so they are refused here, before ITK sees the file. ElementDataFile is a std::string.
    if (key.size() >= kMaxMetaIOString) {
      throw InputError(name, "header", "a key of " + std::to_string(key.size()) + " characters ('" + key.substr(0, 40) +
                                           "...'): MetaImage keys are at most " + std::to_string(kMaxMetaIOString - 1));
    }
    if (value.size() >= (key == "ElementDataFile" ? kMaxMetaIOFieldBytes : kMaxMetaIOString)) {
      throw InputError(name, key, "a value of " + std::to_string(value.size()) + " characters: MetaImage header values are at most " +
                                      std::to_string((key == "ElementDataFile" ? kMaxMetaIOFieldBytes : kMaxMetaIOString) - 1));
    }
    h.fields[key] = value;
    if (key != "ElementDataFile") continue;
    h.data_start = position;
    return h;
  }
}

// Inflates (zlib or gzip headers, as MetaIO's MET_PerformUncompression) `compressed` bytes starting at
// `offset` of `file`; InputError unless the stream ends and gives exactly `expected` bytes. Returns
// the compressed bytes the stream took.
uint64_t check_compressed(const fs::path& file, uint64_t offset, uint64_t available, uint64_t expected, const std::string& name) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  z_stream z{};
  if (inflateInit2(&z, 47) != Z_OK) throw RuntimeError(name + ": zlib cannot start");
  std::vector<unsigned char> input(1 << 16), output(1 << 18);
  uint64_t produced = 0, consumed = 0;
  int status = Z_OK;
  while (status != Z_STREAM_END) {
    if (z.avail_in == 0) {
      const std::size_t want = static_cast<std::size_t>(std::min<uint64_t>(input.size(), available - consumed));
      in.read(reinterpret_cast<char*>(input.data()), static_cast<std::streamsize>(want));
      const std::size_t got = static_cast<std::size_t>(in.gcount());
      if (got == 0) break;
      consumed += got;
      z.next_in = input.data();
      z.avail_in = static_cast<uInt>(got);
    }
    z.next_out = output.data();
    z.avail_out = static_cast<uInt>(output.size());
    status = inflate(&z, Z_NO_FLUSH);
    produced += output.size() - z.avail_out;
    if (status != Z_OK && status != Z_STREAM_END) {
      const std::string why = z.msg ? z.msg : "zlib error " + std::to_string(status);
      inflateEnd(&z);
      throw InputError(name, "CompressedData", "the compressed voxel data are damaged: " + why);
    }
    if (produced > expected) break;
  }
  const uint64_t used = consumed - z.avail_in;
  inflateEnd(&z);
  if (status != Z_STREAM_END || produced != expected) {
    throw InputError(name, "CompressedData",
                     status != Z_STREAM_END && produced <= expected
                         ? "the compressed voxel data are cut short: they give " + std::to_string(produced) + " of " +
                               std::to_string(expected) + " bytes"
                         : "the compressed voxel data give more than the header's " + std::to_string(expected) + " bytes");
  }
  return used;
}

}  // namespace

void check_data_file_beside_header(const fs::path& header, const fs::path& data_file, const std::string& field) {
  const std::string name = header.string();
  if (data_file.is_absolute()) {
    throw InputError(name, field, "'" + data_file.string() + "' is an absolute path: data files must lie beside the header "
                                  "(ctsurg-import --allow-data-outside to read it anyway)");
  }
  for (const auto& part : data_file.lexically_normal()) {
    if (part == "..") {
      throw InputError(name, field, "'" + data_file.string() + "' leads out of the header's folder "
                                    "(ctsurg-import --allow-data-outside to read it anyway)");
    }
  }
  std::error_code ec;
  const fs::path folder = fs::weakly_canonical(fs::absolute(header).parent_path(), ec);
  const fs::path target = fs::weakly_canonical(fs::absolute(header).parent_path() / data_file, ec);
  const auto [f, t] = std::mismatch(folder.begin(), folder.end(), target.begin(), target.end());
  if (f != folder.end()) {
    throw InputError(name, field, "'" + data_file.string() + "' is a link to '" + target.string() +
                                  "', outside the header's folder (ctsurg-import --allow-data-outside to read it anyway)");
  }
}

std::vector<fs::path> verify_metaimage_file(const fs::path& path, bool data_files_anywhere,
                                            std::vector<std::string>* warnings) {
  const std::string name = path.string();
  check_input_file(path);
  const MetaImageHeader h = read_header(path, name);
  const auto field = [&](const std::string& key) -> const std::string* {
    const auto it = h.fields.find(key);
    return it == h.fields.end() ? nullptr : &it->second;
  };
  const std::string* ndims_text = field("NDims");
  if (!ndims_text) throw InputError(name, "NDims", "missing");
  const int64_t ndims = whole_number(*ndims_text, name, "NDims", 2, 4);
  const std::string* dim_text = field("DimSize");
  if (!dim_text) throw InputError(name, "DimSize", "missing");
  std::istringstream dims_in(*dim_text);
  std::vector<int64_t> dims;
  for (std::string item; dims_in >> item;) {
    if (dims.size() == static_cast<std::size_t>(ndims)) throw InputError(name, "DimSize", "has more than NDims values");
    dims.push_back(whole_number(item, name, "DimSize", 1, int64_t{1} << 40));
  }
  if (dims.size() != static_cast<std::size_t>(ndims)) {
    throw InputError(name, "DimSize", "has " + std::to_string(dims.size()) + " values, NDims says " + std::to_string(ndims));
  }
  if (ndims == 4 && dims[3] != 1) throw InputError(name, "DimSize", "4D image: ctsurg reads one 3D volume");
  const std::string* type = field("ElementType");
  if (!type || element_sizes().count(*type) == 0) {
    throw InputError(name, "ElementType", (type ? "'" + *type + "'" : std::string("missing")) +
                                              ": expected a scalar type, MET_CHAR .. MET_DOUBLE");
  }
  if (const std::string* channels = field("ElementNumberOfChannels")) {
    if (whole_number(*channels, name, "ElementNumberOfChannels", 1, 1 << 20) != 1) {
      throw InputError(name, "ElementNumberOfChannels", "is " + *channels + ": ctsurg reads scalar images");
    }
  }
  if (const std::string* binary = field("BinaryData"); binary && !is_true(*binary)) {
    throw InputError(name, "BinaryData", "is False: ASCII voxel data are not read (write binary data)");
  }
  int64_t voxels = 1;
  for (const int64_t d : dims) {
    if (__builtin_mul_overflow(voxels, d, &voxels) || voxels > ImageGeometry::kMaxVoxels) {
      throw InputError(name, "DimSize", "more than 2^48 voxels: not an image");
    }
  }
  const uint64_t expected = static_cast<uint64_t>(voxels) * static_cast<uint64_t>(element_sizes().at(*type));
  const bool compressed = field("CompressedData") && is_true(*field("CompressedData"));
  const int64_t header_size =
      field("HeaderSize") ? whole_number(*field("HeaderSize"), name, "HeaderSize", -1, int64_t{1} << 40) : 0;

  // The data files.
  const std::string& data = *field("ElementDataFile");
  const fs::path folder = path.parent_path();
  const bool local = data == "LOCAL";
  const std::vector<fs::path> files = detached_data_file_names(path);  // as named, relative to its folder
  if (!local && files.empty()) throw InputError(name, "ElementDataFile", "names no data file");
  if (compressed && files.size() > 1) {
    throw InputError(name, "CompressedData", "compressed data in several files are not read; write one file");
  }
  std::vector<fs::path> resolved;
  for (const auto& f : files) {
    if (!data_files_anywhere) check_data_file_beside_header(path, f, "ElementDataFile");
    resolved.push_back(f.is_absolute() ? f : folder / f);
    check_input_file(resolved.back(), expected == 0);
  }

  // The data bytes.
  const auto stream_of = [&](const fs::path& file, uint64_t start) {
    const uint64_t size = fs::file_size(file);
    if (header_size > 0) start += static_cast<uint64_t>(header_size);
    if (start > size) throw InputError(name, "HeaderSize", "skips past the end of '" + file.string() + "'");
    return std::pair{start, size - start};
  };
  if (compressed) {
    const fs::path file = local ? path : resolved.front();
    const auto [start, available] = stream_of(file, local ? h.data_start : 0);
    const uint64_t used = check_compressed(file, start, available, expected, name);
    if (const std::string* size_text = field("CompressedDataSize")) {
      const int64_t declared = whole_number(*size_text, name, "CompressedDataSize", 0, int64_t{1} << 50);
      if (static_cast<uint64_t>(declared) != used) {
        throw InputError(name, "CompressedDataSize", "says " + std::to_string(declared) + " bytes, the compressed stream is " +
                                                         std::to_string(used));
      }
    }
    if (available > used && warnings) {
      warnings->push_back(std::to_string(available - used) + " bytes after the compressed voxel data are ignored");
    }
    return resolved;
  }
  uint64_t have = 0;
  if (local) {
    have = stream_of(path, h.data_start).second;
  } else if (header_size == -1) {
    for (const auto& f : resolved) have += fs::file_size(f);  // MetaIO reads the data from the end of each file
    if (have > expected) have = expected;
  } else {
    for (const auto& f : resolved) have += stream_of(f, 0).second;
  }
  if (have < expected) {
    throw InputError(name, "ElementDataFile",
                     "the voxel data are cut short: DimSize x ElementType need " + std::to_string(expected) +
                         " bytes, the data " + std::string(local ? "after the header" : "files") + " hold " +
                         std::to_string(have));
  }
  if (have > expected && warnings) {
    warnings->push_back(std::to_string(have - expected) + " bytes after the voxel data are not part of the image (ignored)");
  }
  return resolved;
}

}  // namespace ctsurg

#include "ctsurg/preprocess/detached_data_files.h"

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"

#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

constexpr long kMaxFiles = 1000000;

// True when `pattern` holds exactly one integer conversion (%d, %i, %u, %x, %X or %o, with flags
// and a width: "slice%03d.raw") and otherwise only "%%": anything else would make snprintf read an
// argument that is not there.
bool is_integer_pattern(const std::string& pattern) {
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') continue;
    if (++i < pattern.size() && pattern[i] == '%') continue;
    while (i < pattern.size() && std::string("-+ #0").find(pattern[i]) != std::string::npos) ++i;
    while (i < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[i]))) ++i;
    if (i >= pattern.size() || std::string("diuxXo").find(pattern[i]) == std::string::npos) return false;
    ++conversions;
  }
  return conversions == 1;
}

}  // namespace

std::vector<fs::path> detached_data_file_names(const fs::path& header) {
  const ImageFileFormat format = image_file_format(header);
  if (format == ImageFileFormat::Nifti) return {};
  const bool nrrd = format == ImageFileFormat::Nrrd;
  std::ifstream in(header);
  std::string line;
  std::vector<fs::path> files;
  bool list = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (list) {
      if (files.size() >= static_cast<std::size_t>(kMaxFiles)) {
        throw InputError(header.string(), "data file", "LIST of more than a million files");
      }
      if (!line.empty()) files.emplace_back(line);
      continue;
    }
    if (line.empty()) {
      if (nrrd) break;  // end of a NRRD header
      continue;
    }
    const auto sep = line.find(nrrd ? ':' : '=');
    if (sep == std::string::npos) continue;
    std::string key = line.substr(0, sep);
    while (!key.empty() && key.back() == ' ') key.pop_back();
    if (nrrd ? (key != "data file" && key != "datafile") : key != "ElementDataFile") continue;
    std::istringstream value(line.substr(sep + 1));
    std::string first;
    value >> first;
    if (first == "LIST") {
      list = true;
      continue;
    }
    if (first == "LOCAL") break;
    long lo = 0, hi = 0, step = 0;
    if (first.find('%') != std::string::npos && value >> lo >> hi >> step) {
      if (!is_integer_pattern(first)) {
        throw InputError(header.string(), key, "'" + first + "' is not a file name pattern with one integer field (%d)");
      }
      if (step == 0 || (hi - lo) / step < 0 || (hi - lo) / step >= kMaxFiles) {
        throw InputError(header.string(), key, "min " + std::to_string(lo) + " max " + std::to_string(hi) + " step " +
                                                   std::to_string(step) + " name no file or more than a million");
      }
      for (long n = lo; step > 0 ? n <= hi : n >= hi; n += step) {
        char name[4096];
        std::snprintf(name, sizeof name, first.c_str(), n);
        files.emplace_back(name);
      }
    } else {
      files.emplace_back(first);
    }
    if (!nrrd) break;  // ElementDataFile is the last MetaImage header field
  }
  return files;
}

std::vector<fs::path> detached_data_files(const fs::path& header) {
  std::vector<fs::path> files;
  for (const auto& name : detached_data_file_names(header)) files.push_back(name.is_absolute() ? name : header.parent_path() / name);
  return files;
}

}  // namespace ctsurg

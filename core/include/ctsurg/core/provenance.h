// Provenance: every file a ctsurg tool writes records which tool made it, its version, the full
// command line, the SHA-256 of every input file, and the provenance of inputs that are themselves
// ctsurg HDF5 files (so a scenario traces back to the CT it came from). Stored as attributes of the
// group /provenance (docs/formats.md).
#pragma once

#include "ctsurg/core/hdf5_file.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ctsurg {

struct InputRecord {
  std::string path;    // as given on the command line
  std::string sha256;  // of the file's bytes
  uint64_t bytes = 0;
};

struct Provenance {
  std::string tool;          // e.g. "ctsurg-import"
  std::string version;       // ctsurg version
  std::vector<std::string> command_line;  // argv
  std::vector<InputRecord> inputs;
  nlohmann::json upstream = nlohmann::json::array();  // provenance of ctsurg HDF5 inputs

  // Hashes `path` and records it. When it is a ctsurg HDF5 file, its provenance goes to upstream.
  void add_input(const std::filesystem::path& path);
  nlohmann::json to_json() const;
  void write(h5::Group& root) const;
  // Reads /provenance of a ctsurg file as JSON; null when the file has none.
  static nlohmann::json read(const h5::Group& root);
};

}  // namespace ctsurg

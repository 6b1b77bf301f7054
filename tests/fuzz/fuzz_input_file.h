// The fuzz targets' way into ctsurg's readers, which read files: each input is written to a file in
// a private folder (made once per process with mkdtemp, so a header naming data files "beside" it
// can only reach what the target itself wrote there), and the reader's refusals, which are the
// expected outcome for almost every input, are swallowed. Anything else escaping a reader (another
// exception type, a crash, a sanitizer report, a hang, an out-of-memory) is a finding.
#pragma once

#include "ctsurg/core/error.h"

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace ctsurg::fuzz {

// The private folder of this process.
inline const std::filesystem::path& folder() {
  static const std::filesystem::path dir = [] {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/ctsurg-fuzz-XXXXXX";
    if (!::mkdtemp(pattern.data())) std::abort();
    return std::filesystem::path(pattern);
  }();
  return dir;
}

// Writes `bytes` to `name` in the private folder and returns its path.
inline std::filesystem::path write_input(const std::string& name, std::string_view bytes) {
  const std::filesystem::path p = folder() / name;
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return p;
}

// Runs `read`, swallowing ctsurg's refusals (InputError: bad input; RuntimeError: out of memory).
template <class Read>
void expect_refusal_or_success(Read&& read) {
  try {
    read();
  } catch (const InputError&) {
  } catch (const RuntimeError&) {
  }
}

}  // namespace ctsurg::fuzz

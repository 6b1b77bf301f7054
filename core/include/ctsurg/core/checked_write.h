// Writing bytes to a file with every error checked: each write(2) (short writes resumed, EINTR
// retried), fsync(2) and close(2). A full disk, a quota or a file-size limit (ulimit -f, with
// SIGXFSZ ignored as the tools do) becomes a RuntimeError naming the file, never a truncated file
// that looks finished. Writers that get bytes from a library (HDF5 file images, Assimp, OpenCV)
// hand them to this function instead of trusting the library's own I/O.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace ctsurg {

// Creates or truncates `path` and writes `bytes` to it, then flushes it to the device. `name` is
// the file named in messages (the final output, not the temporary file being written).
void write_file_checked(const std::filesystem::path& path, std::string_view bytes, const std::string& name);

}  // namespace ctsurg

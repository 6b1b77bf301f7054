// Write-then-rename outputs: a tool writes to a temporary file beside the final one and renames it
// into place only when everything succeeded, so a failure or a kill never leaves a partial output
// and never destroys what the user already had under that name.
#pragma once

#include <filesystem>
#include <string>

namespace ctsurg {

class AtomicOutput {
 public:
  // Checks that the parent folder exists and is writable (InputError naming the path otherwise)
  // and picks a unique temporary name ".tmp-<pid>-<n>-<name>" in that folder (same suffix as the
  // final name, so suffix-driven writers such as ITK's choose the right format). The temporary file is
  // removed on destruction unless commit() succeeded, and also if the process gets SIGINT/SIGTERM.
  explicit AtomicOutput(std::filesystem::path final_path);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  const std::filesystem::path& path() const { return final_; }       // where the result will be
  const std::filesystem::path& temp_path() const { return temp_; }   // where to write it now
  // Flushes the temporary file to disk and renames it over the final path (atomic on POSIX).
  void commit();
  bool committed() const { return committed_; }

 private:
  std::filesystem::path final_, temp_;
  int slot_ = -1;
  bool committed_ = false;
};

// Throws InputError naming `path` when it cannot become an output (missing or unwritable folder,
// or a folder at that path). Tools call it before long work so a bad output path fails at once.
void check_output_path(const std::filesystem::path& path);

// Writes `bytes` to `path` through an AtomicOutput.
void write_file_atomically(const std::filesystem::path& path, const std::string& bytes);

}  // namespace ctsurg

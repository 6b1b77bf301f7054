// Write-then-rename outputs: a tool writes to a temporary file beside the final one and renames it
// into place only when everything succeeded, so a failure or a kill never leaves a partial output
// and never destroys what the user already had under that name. Outputs that belong together (an
// HDF5 file and its XDMF sidecar, a grid and its preview, a .gltf and its .bin) are committed as one
// unit (commit_together), and the output paths are checked before the work starts
// (check_output_paths): a folder that is missing or not writable, a FIFO or a name too long for the
// file system, an output that is one of the inputs, or two outputs that are the same file.
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ctsurg {

class AtomicOutput {
 public:
  // Checks the path (check_output_path) and picks a unique temporary name ".tmp-<pid>-<n>-<name>"
  // in the same folder (same suffix as the final name, so suffix-driven writers such as ITK's
  // choose the right format). The temporary file is removed on destruction unless the output was
  // committed, and also if the process gets SIGINT/SIGTERM/SIGHUP.
  explicit AtomicOutput(std::filesystem::path final_path);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  const std::filesystem::path& path() const { return final_; }       // where the result will be
  const std::filesystem::path& temp_path() const { return temp_; }   // where to write it now
  // commit_together() with this output alone.
  void commit();
  bool committed() const { return committed_; }

 private:
  friend void commit_together(std::span<AtomicOutput* const> outputs);
  void mark_committed();
  std::filesystem::path final_, temp_;
  int slot_ = -1;
  bool committed_ = false;
};

// Commits `outputs` as one unit. Each temporary file is flushed to the device (fsync; an error is a
// RuntimeError naming the output), then, with an exclusive lock (flock) on every output folder so
// that two runs writing the same outputs commit one after the other, each one is renamed over its
// final path, the previous file kept as a hard-link backup until all are in place. When a rename
// fails, the outputs already renamed are put back (previous files restored, new ones removed) and
// RuntimeError is thrown: afterwards either every output is new or every one is as it was.
// SIGINT/SIGTERM/SIGHUP are held during the renames. Outputs already committed are skipped.
void commit_together(std::span<AtomicOutput* const> outputs);

// Outputs that are committed as one unit (commit_together): writers add the files they make, the
// tool commits the unit once every file of the run is written.
class OutputUnit {
 public:
  // A new output in the unit (see AtomicOutput); the unit owns it.
  AtomicOutput& add(const std::filesystem::path& final_path);
  void commit();

 private:
  std::vector<std::unique_ptr<AtomicOutput>> outputs_;
};

// Throws InputError naming `path` when it cannot become an output: empty, a folder, an existing
// FIFO, socket or device, a missing or unwritable folder, or a file name longer than the folder's
// file system allows (the temporary name adds up to 28 characters).
void check_output_path(const std::filesystem::path& path);

// check_output_path() on every output, then InputError when an output is the same file as an input
// (by name, or by hard or symbolic link: writing it would replace the input) or when two outputs
// are the same file. Tools call it with every file they will write (sidecars included) and every
// file they read, before long work, so a bad output path fails at once.
void check_output_paths(const std::vector<std::filesystem::path>& outputs,
                        const std::vector<std::filesystem::path>& inputs);

// Writes `bytes` to `path` through an AtomicOutput.
void write_file_atomically(const std::filesystem::path& path, const std::string& bytes);

}  // namespace ctsurg

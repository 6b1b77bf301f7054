// Errors raised by the ctsurg libraries. Tools map them to exit codes (see tool_app.h):
// InputError -> 2 (bad usage or bad input), anything else -> 1 (runtime failure).
#pragma once

#include <stdexcept>
#include <string>

namespace ctsurg {

// A number as a message shows it ("got -1.5"): the stream's default form, 6 significant digits.
std::string message_number(double v);

// Bad input: a file, a field of it, or an option is missing, malformed or out of range.
// The message names the file (or option), the field and the problem:
//   "heart.nii.gz: pixdim[1]: spacing must be positive, got -1.5"
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string field, std::string problem);
  const std::string& file() const noexcept { return file_; }
  const std::string& field() const noexcept { return field_; }
  const std::string& problem() const noexcept { return problem_; }

 private:
  std::string file_, field_, problem_;
};

// A failure while doing valid work (I/O error, out of memory, numerical breakdown).
class RuntimeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace ctsurg

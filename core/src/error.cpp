#include "ctsurg/core/error.h"

#include <sstream>

namespace ctsurg {

std::string message_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

namespace {
std::string compose(const std::string& file, const std::string& field, const std::string& problem) {
  std::string m = file.empty() ? std::string("<input>") : file;
  if (!field.empty()) m += ": " + field;
  return m + ": " + problem;
}
}  // namespace

InputError::InputError(std::string file, std::string field, std::string problem)
    : std::runtime_error(compose(file, field, problem)),
      file_(std::move(file)),
      field_(std::move(field)),
      problem_(std::move(problem)) {}

}  // namespace ctsurg

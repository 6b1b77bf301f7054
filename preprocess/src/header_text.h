// Text helpers shared by the readers of text headers (MetaImage's "Key = Value", NRRD's "key: value" in
// 3D Slicer segmentations); not public.
#pragma once

#include <string>

namespace ctsurg {

// s without leading and trailing spaces, tabs and carriage returns.
inline std::string trim_header_text(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

}  // namespace ctsurg

// The data files a detached header points to: NRRD ("data file:") and MetaImage
// ("ElementDataFile ="), each as a single name, a printf-style pattern with min max step, or LIST
// followed by names. Empty for attached data (and MetaImage LOCAL).
#pragma once

#include <filesystem>
#include <vector>

namespace ctsurg {

// The names as the header writes them (relative to its folder unless absolute).
std::vector<std::filesystem::path> detached_data_file_names(const std::filesystem::path& header);
// The same resolved against the header's folder.
std::vector<std::filesystem::path> detached_data_files(const std::filesystem::path& header);

}  // namespace ctsurg

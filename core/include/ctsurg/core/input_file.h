// The first check of every file a tool reads: it exists, is a regular file (a folder, a FIFO, a
// socket or a device would hang a library or read as garbage) and can be opened. Readers call it
// before handing the path to a library, so the message names the user's file and says what it is.
#pragma once

#include <filesystem>

namespace ctsurg {

// InputError(path, "", ...) unless `path` is a readable regular file (symbolic links followed);
// also when it is empty and `allow_empty` is false.
void check_input_file(const std::filesystem::path& path, bool allow_empty = false);

}  // namespace ctsurg

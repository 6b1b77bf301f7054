#include "ctsurg/core/input_file.h"

#include "ctsurg/core/error.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace ctsurg {

namespace {

// What a non-regular file is, for the message.
std::string input_kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  return "not a regular file";
}

}  // namespace

void check_input_file(const std::filesystem::path& path, bool allow_empty) {
  const std::string name = path.string();
  if (name.empty()) throw InputError("<input>", "path", "the input path is empty");
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) throw InputError(name, "", "file does not exist");
    throw InputError(name, "", std::string("cannot be read: ") + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) throw InputError(name, "", "is " + input_kind_of(st.st_mode) + ", expected a file");
  // O_NONBLOCK: never wait on the file while checking it (it is regular, but be safe against races).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw InputError(name, "", std::string("cannot be opened: ") + std::strerror(errno));
  ::close(fd);
  if (st.st_size == 0 && !allow_empty) throw InputError(name, "", "file is empty");
}

}  // namespace ctsurg

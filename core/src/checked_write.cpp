#include "ctsurg/core/checked_write.h"

#include "ctsurg/core/error.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace ctsurg {

void write_file_checked(const std::filesystem::path& path, std::string_view bytes, const std::string& name) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw RuntimeError(name + ": cannot create the file: " + std::strerror(errno));
  const auto fail = [&](const char* what) {
    const int e = errno;
    ::close(fd);
    throw RuntimeError(name + ": " + what + ": " + std::strerror(e));
  };
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write failed");
    }
    if (n == 0) {
      errno = ENOSPC;
      fail("write failed");
    }
    done += static_cast<std::size_t>(n);
  }
  // Delayed allocation (ext4, XFS, NFS) reports a full disk only here.
  if (::fsync(fd) != 0) fail("write failed (fsync)");
  if (::close(fd) != 0) throw RuntimeError(name + ": write failed (close): " + std::strerror(errno));
}

}  // namespace ctsurg

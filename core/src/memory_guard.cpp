#include "ctsurg/core/memory_guard.h"

#include "ctsurg/core/error.h"

#include <pthread.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#if defined(__SANITIZE_ADDRESS__)
#define CTSURG_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CTSURG_SANITIZED 1
#endif
#endif
#ifndef CTSURG_SANITIZED
#define CTSURG_SANITIZED 0
#endif

namespace ctsurg {

namespace {

constexpr uint64_t kMiB = 1024 * 1024;
// Under a cap, room left for what libraries allocate without asking the guard (thread pools, I/O
// buffers), so that the guard refuses first and a library seldom meets the hard limit itself.
constexpr uint64_t kHeadroom = 16 * kMiB;
// Under a cap, the default stack of new threads (ITK's pool, OpenMP's team): reserved stacks count
// as data memory, and glibc's default of 8 MiB each would spend a small cap on threads.
constexpr std::size_t kCappedThreadStack = 2 * kMiB;

// A "Key: <n> kB" line of a /proc file, in bytes (0 when absent).
uint64_t proc_kib(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) != 0) continue;
    std::istringstream value(line.substr(key.size()));
    uint64_t kib = 0;
    return value >> kib ? kib * 1024 : 0;
  }
  return 0;
}

std::string mib(uint64_t bytes) { return std::to_string(bytes / kMiB) + " MiB"; }

}  // namespace

std::optional<uint64_t> memory_cap_bytes() {
  const char* text = std::getenv("CTSURG_MAX_MEMORY_MB");
  if (text == nullptr) return std::nullopt;
  const std::string s = text;
  const bool digits = !s.empty() && s.size() <= 13 && s.find_first_not_of("0123456789") == std::string::npos;
  const uint64_t mb = digits ? std::stoull(s) : 0;
  if (!digits || mb < 1 || mb >= (uint64_t{1} << 40)) {
    throw InputError("CTSURG_MAX_MEMORY_MB", "",
                     "must be a whole number of MiB from 1 to 2^40, got '" + s + "' (unset it for no cap)");
  }
  return mb * kMiB;
}

uint64_t process_memory_bytes() {
  return CTSURG_SANITIZED ? proc_kib("/proc/self/status", "RssAnon:") : proc_kib("/proc/self/status", "VmData:");
}

uint64_t available_memory_bytes() {
  uint64_t available = proc_kib("/proc/meminfo", "MemAvailable:");
  if (available == 0) available = std::numeric_limits<uint64_t>::max();
  if (const auto cap = memory_cap_bytes()) {
    const uint64_t used = process_memory_bytes() + kHeadroom;
    available = std::min(available, *cap > used ? *cap - used : 0);
  }
  return available;
}

std::string memory_cap_note() {
  const char* text = std::getenv("CTSURG_MAX_MEMORY_MB");
  return text ? std::string("CTSURG_MAX_MEMORY_MB=") + text + " caps this process's data memory" : std::string();
}

void check_allocation(uint64_t count, uint64_t bytes_per_item, const std::string& file, const std::string& field) {
  if (bytes_per_item != 0 && count > std::numeric_limits<uint64_t>::max() / bytes_per_item) {
    throw InputError(file, field,
                     "asks for " + std::to_string(count) + " values of " + std::to_string(bytes_per_item) +
                         " bytes: more than 2^64 bytes (refused before allocating)");
  }
  const uint64_t bytes = count * bytes_per_item;
  const uint64_t available = available_memory_bytes();
  if (bytes <= available) return;
  std::ostringstream s;
  s << file << ": " << field << ": needs " << mib(bytes) << " for " << count << " values, but only " << mib(available)
    << " of memory are available";
  const std::string cap = memory_cap_note();
  if (!cap.empty()) s << " (" << cap << "; the process uses " << mib(process_memory_bytes()) << ")";
  s << "; refused before allocating";
  throw RuntimeError(s.str());
}

void apply_memory_cap() {
  const auto cap = memory_cap_bytes();
  if (!cap) return;
  const uint64_t used = process_memory_bytes();
  if (used >= *cap) {
    throw RuntimeError(memory_cap_note() + ", but the process already uses " + mib(used) + " at start");
  }
  if (CTSURG_SANITIZED) return;
  pthread_attr_t attr;
  if (pthread_attr_init(&attr) == 0) {
    pthread_attr_setstacksize(&attr, kCappedThreadStack);
    pthread_setattr_default_np(&attr);
    pthread_attr_destroy(&attr);
  }
  rlimit limit{};
  if (::getrlimit(RLIMIT_DATA, &limit) != 0) return;
  limit.rlim_cur = limit.rlim_max == RLIM_INFINITY ? *cap : std::min<rlim_t>(*cap, limit.rlim_max);
  if (::setrlimit(RLIMIT_DATA, &limit) != 0) {
    throw RuntimeError(memory_cap_note() + ", but the limit cannot be set: " + std::strerror(errno));
  }
}

}  // namespace ctsurg

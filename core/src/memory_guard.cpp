#include "ctsurg/core/memory_guard.h"

#include "ctsurg/core/error.h"

#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace ctsurg {

uint64_t available_memory_bytes() {
  uint64_t available = std::numeric_limits<uint64_t>::max();
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  uint64_t kib = 0;
  std::string unit;
  while (meminfo >> key >> kib >> unit) {
    if (key == "MemAvailable:") {
      available = kib * 1024;
      break;
    }
  }
  if (const char* cap = std::getenv("CTSURG_MAX_MEMORY_MB")) {
    char* end = nullptr;
    const unsigned long long mb = std::strtoull(cap, &end, 10);
    if (end != cap && mb > 0 && mb * 1024ull * 1024ull < available) available = mb * 1024ull * 1024ull;
  }
  return available;
}

void check_allocation(uint64_t count, uint64_t bytes_per_item, const std::string& file, const std::string& field) {
  const uint64_t available = available_memory_bytes();
  const bool overflow = bytes_per_item != 0 && count > std::numeric_limits<uint64_t>::max() / bytes_per_item;
  const uint64_t bytes = overflow ? std::numeric_limits<uint64_t>::max() : count * bytes_per_item;
  if (overflow || bytes > available) {
    std::ostringstream s;
    s << "needs " << (overflow ? std::string("more than 2^64 bytes") : std::to_string(bytes / (1024 * 1024)) + " MiB")
      << " for " << count << " values, but only " << available / (1024 * 1024)
      << " MiB of memory are available (refused before allocating)";
    throw InputError(file, field, s.str());
  }
}

}  // namespace ctsurg

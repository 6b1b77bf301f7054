// Refuse allocations that cannot fit before making them, so an absurd header gives a clear error
// instead of an out-of-memory kill.
#pragma once

#include <cstdint>
#include <string>

namespace ctsurg {

// Bytes of memory this process may still use: MemAvailable from /proc/meminfo, lowered by the
// environment variable CTSURG_MAX_MEMORY_MB when it is set.
uint64_t available_memory_bytes();

// Throws InputError(file, field, ...) when `bytes` exceeds available_memory_bytes(); the message
// gives both numbers in MiB. `count` and `bytes_per_item` are checked for overflow.
void check_allocation(uint64_t count, uint64_t bytes_per_item, const std::string& file, const std::string& field);

}  // namespace ctsurg

// Refuse allocations that cannot fit before making them, so an absurd header or option gives a
// clear error instead of an out-of-memory kill, and cap what a process really uses.
//
// CTSURG_MAX_MEMORY_MB caps the process's data memory (heap and private anonymous mappings: what
// Linux's RLIMIT_DATA counts; shared library code is not counted). The tools validate it at start
// (a whole number of MiB >= 1, otherwise exit 2) and make it a hard limit (setrlimit(RLIMIT_DATA)),
// so an allocation that the guard did not foresee fails as "out of memory" (exit 1) instead of
// exceeding it; new threads then get 2 MiB stacks (reserved stacks count as data memory) and the
// guard keeps 16 MiB for what libraries allocate without asking it. Sanitizer builds reserve
// terabytes of shadow memory, so there the hard limit is not set and the guard counts resident
// anonymous memory instead.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace ctsurg {

// The cap in bytes from CTSURG_MAX_MEMORY_MB, or nullopt when unset. InputError naming the variable
// when it is set to anything but a whole number of MiB in [1, 2^40).
std::optional<uint64_t> memory_cap_bytes();

// Bytes of data memory this process uses now (VmData of /proc/self/status; VmRSS's anonymous part,
// RssAnon, in sanitizer builds).
uint64_t process_memory_bytes();

// Bytes this process may still allocate: MemAvailable from /proc/meminfo, lowered to the cap minus
// process_memory_bytes() and the 16 MiB headroom when CTSURG_MAX_MEMORY_MB is set.
uint64_t available_memory_bytes();

// Throws when `count` x `bytes_per_item` bytes cannot be allocated now: RuntimeError (exit 1: out of
// memory, docs/formats.md) naming `file` and `field` with both sizes in MiB and what limits them;
// InputError (exit 2: an absurd size) when the product overflows 2^64 bytes.
void check_allocation(uint64_t count, uint64_t bytes_per_item, const std::string& file, const std::string& field);

// Validates CTSURG_MAX_MEMORY_MB and, when set, makes it the hard limit of this process
// (RLIMIT_DATA; not in sanitizer builds). RuntimeError when the process already uses more.
void apply_memory_cap();

// "" or, when a cap is set, a sentence naming it, for out-of-memory messages.
std::string memory_cap_note();

}  // namespace ctsurg

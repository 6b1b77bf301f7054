// Content hashes for provenance records.
#pragma once

#include <filesystem>
#include <string>

namespace ctsurg {

// SHA-256 of a file's bytes as 64 lowercase hex digits (OpenSSL EVP). Throws InputError when the
// file cannot be read.
std::string sha256_file(const std::filesystem::path& path);

}  // namespace ctsurg

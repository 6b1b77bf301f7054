// Checks shared by the tests of ctsurg's file verification: a file refused both by its verifier and
// by read_image_file, naming the file, a field and (optionally) words of the problem.
#pragma once

#include "ctsurg/core/error.h"
#include "ctsurg/preprocess/image_file_reader.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>

namespace ctsurg::test {

// `verify(path)` and read_image_file(path) both throw an InputError naming `path`, whose field
// contains `field` (or equals it, with `exact_field`) and whose message contains `mention`.
inline void expect_refused(const std::filesystem::path& path, const std::function<void(const std::filesystem::path&)>& verify,
                           const std::string& field, const std::string& mention = "", bool exact_field = false) {
  for (const bool full_read : {false, true}) {
    try {
      if (full_read) {
        read_image_file(path);
      } else {
        verify(path);
      }
      ADD_FAILURE() << path << " was accepted (expected a refusal naming " << field << ")";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path.string());
      if (exact_field) {
        EXPECT_EQ(e.field(), field) << e.what();
      } else {
        EXPECT_NE(e.field().find(field), std::string::npos) << "field '" << e.field() << "', expected " << field << ": " << e.what();
      }
      EXPECT_NE(std::string(e.what()).find(mention), std::string::npos) << e.what();
    }
  }
}

}  // namespace ctsurg::test

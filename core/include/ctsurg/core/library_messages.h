// Messages that libraries print themselves. ITK, GDCM, the NIfTI library, OpenCV and Assimp write
// warnings and errors straight to stderr, so a user saw library noise before (or instead of)
// ctsurg's own message. A LibraryMessages object redirects the process's stderr (file descriptor
// 2) into a private temporary file while a library call runs; take() restores stderr and returns
// the text, which the caller folds into its InputError/RuntimeError (naming the user's file and
// field) or logs as a warning when the call succeeded.
//
// Only for the main thread, around library calls that do not log through spdlog themselves: while
// the object lives, everything written to stderr goes to the capture.
#pragma once

#include <string>

namespace ctsurg {

class LibraryMessages {
 public:
  LibraryMessages();
  ~LibraryMessages();  // restores stderr; text not taken is dropped
  LibraryMessages(const LibraryMessages&) = delete;
  LibraryMessages& operator=(const LibraryMessages&) = delete;

  // Restores stderr (once) and returns what was written meanwhile: lines joined by "; ", blank
  // lines dropped, at most about 600 characters.
  std::string take();

 private:
  int saved_ = -1, capture_ = -1;
  bool restored_ = false;
};

// Raw text a library printed, as take() gives it: lines joined by "; ", blank lines dropped, at most
// about 600 characters.
std::string folded_text(const std::string& raw);

// `problem`, followed by " (the library said: <text>)" when `text` is not empty.
std::string with_library_text(const std::string& problem, const std::string& text);

}  // namespace ctsurg

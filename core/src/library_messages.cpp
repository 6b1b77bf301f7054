#include "ctsurg/core/library_messages.h"

#include "ctsurg/core/anonymous_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>

namespace ctsurg {

namespace {

constexpr std::size_t kMaxText = 600;

}  // namespace

LibraryMessages::LibraryMessages() {
  std::fflush(stderr);
  std::cerr.flush();
  capture_ = anonymous_file();
  if (capture_ < 0) return;  // nothing to capture into: messages stay on stderr
  saved_ = ::dup(2);
  if (saved_ < 0 || ::dup2(capture_, 2) < 0) {
    if (saved_ >= 0) ::close(saved_);
    ::close(capture_);
    saved_ = capture_ = -1;
  }
}

LibraryMessages::~LibraryMessages() { take(); }

std::string LibraryMessages::take() {
  if (restored_ || capture_ < 0) return {};
  restored_ = true;
  std::fflush(stderr);
  std::cerr.flush();
  ::dup2(saved_, 2);
  ::close(saved_);
  std::string raw;
  char buffer[4096];
  ::lseek(capture_, 0, SEEK_SET);
  for (ssize_t n; raw.size() < 64 * 1024 && (n = ::read(capture_, buffer, sizeof buffer)) > 0;) {
    raw.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(capture_);
  return folded_text(raw);
}

std::string folded_text(const std::string& raw) {
  std::istringstream lines(raw);
  std::string line, text;
  while (std::getline(lines, line)) {
    while (!line.empty() && (line.back() == ' ' || line.back() == '\r' || line.back() == '\t')) line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos) continue;
    if (!text.empty()) text += "; ";
    text += line.substr(first);
  }
  if (text.size() > kMaxText) text = text.substr(0, kMaxText) + " ...";
  return text;
}

std::string with_library_text(const std::string& problem, const std::string& text) {
  return text.empty() ? problem : problem + " (the library said: " + text + ")";
}

}  // namespace ctsurg

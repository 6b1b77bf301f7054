#include "ctsurg/core/isolated_call.h"

#include "ctsurg/core/anonymous_file.h"
#include "ctsurg/core/error.h"
#include "ctsurg/core/library_messages.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <string_view>

namespace ctsurg {

namespace {

void write_all(int fd, std::string_view bytes) {
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) std::_Exit(3);
    done += static_cast<std::size_t>(n);
  }
}

std::string read_all(int fd) {
  std::string out;
  ::lseek(fd, 0, SEEK_SET);
  char buffer[1 << 16];
  for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) out.append(buffer, static_cast<std::size_t>(n));
  return out;
}

// The child's outcome: a JSON line ({"ok": true} or the error's kind and fields), then the bytes.
std::string outcome(const nlohmann::json& head, std::string_view bytes = {}) {
  return head.dump() + "\n" + std::string(bytes);
}

}  // namespace

std::string isolated_call(const std::string& input, const std::function<std::string(const ProgressReport& progress)>& work,
                          const ProgressReport& on_progress, double timeout_s) {
  const int result = anonymous_file(), printed_fd = anonymous_file();
  int ticks[2];
  if (result < 0 || printed_fd < 0 || ::pipe2(ticks, O_CLOEXEC) != 0) {
    throw RuntimeError(input + ": cannot start the reading process");
  }
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(result), ::close(printed_fd), ::close(ticks[0]), ::close(ticks[1]);
    throw RuntimeError(input + ": cannot start the reading process: " + std::strerror(errno));
  }
  if (pid == 0) {
    ::close(ticks[0]);
    ::dup2(printed_fd, 2);  // what the libraries print comes back with the outcome
    std::string text;
    try {
      const std::string bytes = work([&](uint64_t done, uint64_t total) {
        const uint64_t report[2] = {done, total};
        (void)!::write(ticks[1], report, sizeof report);  // 16 bytes: one write, below PIPE_BUF
      });
      text = outcome({{"ok", true}}, bytes);
    } catch (const InputError& e) {
      text = outcome({{"error", "input"}, {"file", e.file()}, {"field", e.field()}, {"problem", e.problem()}});
    } catch (const std::bad_alloc&) {
      text = outcome({{"error", "memory"}});
    } catch (const std::exception& e) {
      text = outcome({{"error", "runtime"}, {"what", e.what()}});
    }
    write_all(result, text);
    std::_Exit(0);  // no destructors or exit handlers of the parent's objects in the child
  }
  ::close(ticks[1]);
  // The child's progress until it closes its end (it exits); with a time limit, polled against the
  // deadline, and a child past it is killed: a library looping on a damaged header must not hang the tool.
  const auto start = std::chrono::steady_clock::now();
  bool timed_out = false;
  uint64_t report[2];
  for (;;) {
    if (timeout_s > 0) {
      const double left = timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      pollfd p{ticks[0], POLLIN, 0};
      const int ready = left > 0 ? ::poll(&p, 1, static_cast<int>(std::ceil(left * 1000))) : 0;
      if (ready < 0 && errno == EINTR) continue;
      if (ready == 0) {
        ::kill(pid, SIGKILL);
        timed_out = true;
        break;
      }
    }
    const ssize_t n = ::read(ticks[0], report, sizeof report);
    if (n == 0) break;
    if (n < 0 && errno == EINTR) continue;
    if (n != static_cast<ssize_t>(sizeof report)) break;
    if (on_progress) on_progress(report[0], report[1]);
  }
  ::close(ticks[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string text = read_all(result);
  const std::string printed = folded_text(read_all(printed_fd));
  ::close(result);
  ::close(printed_fd);
  if (timed_out) {
    char limit[32];
    std::snprintf(limit, sizeof limit, "%g", timeout_s);
    throw InputError(input, "", with_library_text(std::string("the reading library did not finish within ") + limit +
                                                      " s: a damaged file (a header the library loops on)",
                                                  printed));
  }
  if (WIFSIGNALED(status) || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || text.empty()) {
    const std::string how = WIFSIGNALED(status) ? std::string("crashed (") + strsignal(WTERMSIG(status)) + ")" : "failed";
    throw InputError(input, "", with_library_text("the reading library " + how + " on it: a damaged file", printed));
  }
  const auto newline = text.find('\n');
  const nlohmann::json head = nlohmann::json::parse(text.substr(0, newline), nullptr, false);
  if (head.is_discarded() || newline == std::string::npos) throw RuntimeError(input + ": the reading process gave no result");
  if (head.value("ok", false)) return text.substr(newline + 1);
  const std::string kind = head.value("error", "");
  if (kind == "input") {
    throw InputError(head.value("file", input), head.value("field", ""), with_library_text(head.value("problem", ""), printed));
  }
  if (kind == "memory") throw std::bad_alloc();
  throw RuntimeError(head.value("what", input + ": the reading process failed"));
}

}  // namespace ctsurg

#include "ctsurg/core/atomic_output.h"

#include "ctsurg/core/error.h"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstring>
#include <fstream>
#include <mutex>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

// Temporary files to delete if the process is interrupted. A fixed table of C strings so that the
// signal handler only calls async-signal-safe functions (unlink, signal, raise).
constexpr int kSlots = 64;
char g_temp_paths[kSlots][4096];
std::atomic<bool> g_slot_used[kSlots];
std::once_flag g_handlers_installed;

extern "C" void remove_temporaries_and_reraise(int sig) {
  for (int s = 0; s < kSlots; ++s) {
    if (g_slot_used[s].load()) ::unlink(g_temp_paths[s]);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

int register_temporary(const fs::path& p) {
  std::call_once(g_handlers_installed, [] {
    std::signal(SIGINT, remove_temporaries_and_reraise);
    std::signal(SIGTERM, remove_temporaries_and_reraise);
    std::signal(SIGHUP, remove_temporaries_and_reraise);
  });
  const std::string s = p.string();
  if (s.size() >= sizeof(g_temp_paths[0])) return -1;
  for (int slot = 0; slot < kSlots; ++slot) {
    bool expected = false;
    if (!g_slot_used[slot].load()) {
      std::memcpy(g_temp_paths[slot], s.c_str(), s.size() + 1);
      if (g_slot_used[slot].compare_exchange_strong(expected, true)) return slot;
    }
  }
  return -1;
}

void unregister_temporary(int slot) {
  if (slot >= 0) g_slot_used[slot].store(false);
}

std::atomic<unsigned> g_counter{0};

}  // namespace

void check_output_path(const fs::path& path) {
  if (path.empty()) throw InputError("<output>", "path", "output path is empty");
  if (fs::is_directory(path)) throw InputError(path.string(), "output", "is a folder, expected a file path");
  fs::path parent = path.parent_path();
  if (parent.empty()) parent = ".";
  if (!fs::is_directory(parent)) {
    throw InputError(path.string(), "output", "folder '" + parent.string() + "' does not exist");
  }
  if (::access(parent.c_str(), W_OK) != 0) {
    throw InputError(path.string(), "output", "folder '" + parent.string() + "' is not writable");
  }
}

AtomicOutput::AtomicOutput(fs::path final_path) : final_(std::move(final_path)) {
  check_output_path(final_);
  fs::path parent = final_.parent_path();
  if (parent.empty()) parent = ".";
  // The temporary name ends with the final name, so libraries that pick a format from the suffix
  // (ITK, OpenCV, niftilib's .gz) write the right thing to it.
  temp_ = parent / (".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(g_counter.fetch_add(1)) + "-" +
                    final_.filename().string());
  slot_ = register_temporary(temp_);
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) {
    std::error_code ec;
    fs::remove(temp_, ec);
  }
  unregister_temporary(slot_);
}

void AtomicOutput::commit() {
  if (committed_) return;
  const int fd = ::open(temp_.c_str(), O_RDONLY);
  if (fd < 0) throw RuntimeError(final_.string() + ": output was not written (temporary file missing)");
  ::fsync(fd);
  ::close(fd);
  std::error_code ec;
  fs::rename(temp_, final_, ec);
  if (ec) throw RuntimeError(final_.string() + ": cannot move the finished output into place: " + ec.message());
  committed_ = true;
  unregister_temporary(slot_);
  slot_ = -1;
}

void write_file_atomically(const fs::path& path, const std::string& bytes) {
  AtomicOutput out(path);
  {
    std::ofstream f(out.temp_path(), std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.close();
    if (!f) throw RuntimeError(path.string() + ": write failed");
  }
  out.commit();
}

}  // namespace ctsurg

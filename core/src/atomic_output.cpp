#include "ctsurg/core/atomic_output.h"

#include "ctsurg/core/checked_write.h"
#include "ctsurg/core/error.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>

namespace fs = std::filesystem;

namespace ctsurg {

namespace {

// Temporary files to delete if the process is interrupted. A fixed table of C strings so that the
// signal handler only calls async-signal-safe functions (unlink, signal, raise).
constexpr int kSlots = 64;
char g_temp_paths[kSlots][4096];
std::atomic<bool> g_slot_used[kSlots];
std::once_flag g_handlers_installed;

// The longest prefix a temporary or backup name adds: ".tmp-" + pid (<= 10 digits) + "-" + counter
// (<= 10 digits) + "-".
constexpr std::size_t kTempPrefixMax = 28;

// The handlers that were there before ours (SIGINT, SIGTERM, SIGHUP), e.g. a server's graceful stop.
constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
struct sigaction g_previous[3];

// A signal while temporaries exist: when the program had its own handler (it means to stop
// gracefully, and its writers then remove their temporaries themselves), that handler runs; when it
// ignored the signal (a background job's SIGINT), nothing happens; otherwise the temporaries are
// deleted and the signal ends the process as it would have.
extern "C" void remove_temporaries_and_reraise(int sig) {
  for (int k = 0; k < 3; ++k) {
    if (kSignals[k] != sig) continue;
    const struct sigaction& previous = g_previous[k];
    if (previous.sa_flags & SA_SIGINFO) {
      if (previous.sa_sigaction != nullptr) return previous.sa_sigaction(sig, nullptr, nullptr);
    } else if (previous.sa_handler == SIG_IGN) {
      return;
    } else if (previous.sa_handler != SIG_DFL) {
      return previous.sa_handler(sig);
    }
  }
  for (int s = 0; s < kSlots; ++s) {
    if (g_slot_used[s].load()) ::unlink(g_temp_paths[s]);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

int register_temporary(const fs::path& p) {
  std::call_once(g_handlers_installed, [] {
    struct sigaction ours {};
    ours.sa_handler = remove_temporaries_and_reraise;
    sigemptyset(&ours.sa_mask);
    for (int k = 0; k < 3; ++k) ::sigaction(kSignals[k], &ours, &g_previous[k]);
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

fs::path folder_of(const fs::path& p) {
  const fs::path parent = p.parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

fs::path hidden_name(const fs::path& final_path, const char* kind) {
  return folder_of(final_path) / (std::string(kind) + std::to_string(::getpid()) + "-" +
                                  std::to_string(g_counter.fetch_add(1)) + "-" + final_path.filename().string());
}

std::string kind_of(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  return "not a regular file";
}

// SIGINT, SIGTERM and SIGHUP held while the outputs are renamed: a kill then arrives after the
// unit is complete (or rolled back), never between two renames.
class HeldSignals {
 public:
  HeldSignals() {
    sigset_t set;
    sigemptyset(&set);
    for (const int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set, s);
    ::pthread_sigmask(SIG_BLOCK, &set, &old_);
  }
  ~HeldSignals() { ::pthread_sigmask(SIG_SETMASK, &old_, nullptr); }

 private:
  sigset_t old_;
};

// An exclusive advisory lock on a folder, so that concurrent commits into it take turns.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& folder) : fd_(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (fd_ >= 0) {
      while (::flock(fd_, LOCK_EX) != 0 && errno == EINTR) {
      }
    }
  }
  ~FolderLock() {
    if (fd_ >= 0) {
      ::fsync(fd_);  // make the renames durable; the data itself was synced before
      ::close(fd_);
    }
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_;
};

void sync_file(const AtomicOutput& out) {
  const int fd = ::open(out.temp_path().c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw RuntimeError(out.path().string() + ": output was not written (temporary file missing)");
  if (::fsync(fd) != 0) {
    const int e = errno;
    ::close(fd);
    throw RuntimeError(out.path().string() + ": cannot flush the output to disk: " + std::strerror(e));
  }
  ::close(fd);
}

}  // namespace

void check_output_path(const fs::path& path) {
  if (path.empty()) throw InputError("<output>", "path", "output path is empty");
  const std::string name = path.string();
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) throw InputError(name, "output", "is a folder, expected a file path");
    if (!S_ISREG(st.st_mode)) throw InputError(name, "output", "is " + kind_of(st.st_mode) + ", not a regular file to replace");
  }
  const fs::path parent = folder_of(path);
  if (!fs::is_directory(parent)) throw InputError(name, "output", "folder '" + parent.string() + "' does not exist");
  if (::access(parent.c_str(), W_OK) != 0) {
    throw InputError(name, "output", "folder '" + parent.string() + "' is not writable");
  }
  const long name_max = ::pathconf(parent.c_str(), _PC_NAME_MAX);
  const std::size_t length = path.filename().string().size();
  if (name_max > 0 && length + kTempPrefixMax > static_cast<std::size_t>(name_max)) {
    throw InputError(name, "output",
                     "the file name is " + std::to_string(length) + " characters; this folder allows " +
                         std::to_string(name_max) + " and the temporary name adds up to " +
                         std::to_string(kTempPrefixMax) + ": use a name of at most " +
                         std::to_string(name_max - static_cast<long>(kTempPrefixMax)) + " characters");
  }
}

void check_output_paths(const std::vector<fs::path>& outputs, const std::vector<fs::path>& inputs) {
  for (const auto& o : outputs) check_output_path(o);
  const auto same_file = [](const fs::path& a, const fs::path& b) {
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec)) {
      const bool same = fs::equivalent(a, b, ec);
      if (!ec) return same;
    }
    return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
  };
  for (const auto& o : outputs) {
    for (const auto& i : inputs) {
      if (!i.empty() && same_file(o, i)) {
        throw InputError(o.string(), "output",
                         "is the input '" + i.string() + "': writing it would replace the input; choose another name");
      }
    }
  }
  for (std::size_t a = 0; a < outputs.size(); ++a) {
    for (std::size_t b = a + 1; b < outputs.size(); ++b) {
      if (same_file(outputs[a], outputs[b])) {
        throw InputError(outputs[b].string(), "output",
                         "is also the output '" + outputs[a].string() + "' of this run; give each output its own name");
      }
    }
  }
}

AtomicOutput::AtomicOutput(fs::path final_path) : final_(std::move(final_path)) {
  check_output_path(final_);
  // The temporary name ends with the final name, so libraries that pick a format from the suffix
  // (ITK, OpenCV, niftilib's .gz) write the right thing to it.
  temp_ = hidden_name(final_, ".tmp-");
  slot_ = register_temporary(temp_);
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) {
    std::error_code ec;
    fs::remove(temp_, ec);
  }
  unregister_temporary(slot_);
}

void AtomicOutput::mark_committed() {
  committed_ = true;
  unregister_temporary(slot_);
  slot_ = -1;
}

void AtomicOutput::commit() {
  AtomicOutput* self[] = {this};
  commit_together(self);
}

void commit_together(std::span<AtomicOutput* const> outputs) {
  std::vector<AtomicOutput*> pending;
  for (AtomicOutput* o : outputs) {
    if (o != nullptr && !o->committed()) pending.push_back(o);
  }
  for (const AtomicOutput* o : pending) sync_file(*o);

  std::vector<fs::path> folders;
  for (const AtomicOutput* o : pending) folders.push_back(fs::weakly_canonical(folder_of(o->path())));
  std::sort(folders.begin(), folders.end());  // a fixed order: two runs never wait on each other
  folders.erase(std::unique(folders.begin(), folders.end()), folders.end());
  const HeldSignals held;
  std::vector<std::unique_ptr<FolderLock>> locks;
  for (const auto& f : folders) locks.push_back(std::make_unique<FolderLock>(f));

  struct Step {
    AtomicOutput* out;
    std::optional<fs::path> backup;  // hard link to the file the output replaces
    bool renamed = false;
  };
  std::vector<Step> steps;
  for (AtomicOutput* o : pending) {
    Step s{o, std::nullopt};
    std::error_code ec;
    if (fs::exists(o->path(), ec)) {
      const fs::path backup = hidden_name(o->path(), ".bak-");
      if (::link(o->path().c_str(), backup.c_str()) == 0) s.backup = backup;
    }
    steps.push_back(std::move(s));
  }
  const auto drop_backups = [&] {
    for (const auto& s : steps) {
      if (s.backup) ::unlink(s.backup->c_str());
    }
  };
  for (auto& s : steps) {
    if (::rename(s.out->temp_path().c_str(), s.out->path().c_str()) == 0) {
      s.renamed = true;
      continue;
    }
    const std::string why = std::strerror(errno);
    for (auto it = steps.rbegin(); it != steps.rend(); ++it) {
      if (!it->renamed) continue;
      if (it->backup) {
        ::rename(it->backup->c_str(), it->out->path().c_str());
        it->backup.reset();
      } else {
        ::unlink(it->out->path().c_str());
      }
    }
    drop_backups();
    throw RuntimeError(s.out->path().string() + ": cannot move the finished output into place: " + why +
                       (steps.size() > 1 ? " (the outputs of this run were not written; earlier files are kept)" : ""));
  }
  drop_backups();
  for (auto& s : steps) s.out->mark_committed();
}

AtomicOutput& OutputUnit::add(const fs::path& final_path) {
  outputs_.push_back(std::make_unique<AtomicOutput>(final_path));
  return *outputs_.back();
}

void OutputUnit::commit() {
  std::vector<AtomicOutput*> all;
  for (const auto& o : outputs_) all.push_back(o.get());
  commit_together(all);
}

void write_file_atomically(const fs::path& path, const std::string& bytes) {
  AtomicOutput out(path);
  write_file_checked(out.temp_path(), bytes, path.string());
  out.commit();
}

}  // namespace ctsurg

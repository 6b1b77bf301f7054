#include "ctsurg/core/atomic_output.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <thread>

namespace fs = std::filesystem;
using namespace ctsurg;

TEST(AtomicOutput, NothingAppearsUntilCommitAndAbandonedWorkIsRemoved) {
  test::TempDir tmp;
  std::ofstream(tmp / "out.txt") << "old";
  {
    AtomicOutput out(tmp / "out.txt");
    std::ofstream(out.temp_path()) << "half";
    EXPECT_EQ(out.temp_path().parent_path(), tmp.path());
  }  // no commit: an exception would land here
  EXPECT_EQ(test::files_in(tmp.path()), std::vector<fs::path>{tmp / "out.txt"});
  std::ifstream in(tmp / "out.txt");
  std::string s;
  in >> s;
  EXPECT_EQ(s, "old");
  {
    AtomicOutput out(tmp / "out.txt");
    std::ofstream(out.temp_path()) << "new";
    out.commit();
  }
  std::ifstream in2(tmp / "out.txt");
  in2 >> s;
  EXPECT_EQ(s, "new");
  EXPECT_EQ(test::files_in(tmp.path()).size(), 1u);
}

TEST(AtomicOutput, BadOutputPathsAreInputErrors) {
  test::TempDir tmp;
  EXPECT_THROW(AtomicOutput(tmp / "missing" / "x.h5"), InputError);
  EXPECT_THROW(AtomicOutput(tmp.path()), InputError);
  EXPECT_THROW(check_output_path(""), InputError);
}

TEST(AtomicOutput, InterruptedToolLeavesNoTemporaryFile) {
  test::TempDir tmp;
  // A child process makes a temporary output and is killed by SIGTERM before committing.
  const pid_t pid = fork();
  if (pid == 0) {
    AtomicOutput out(tmp / "x.h5");
    std::ofstream(out.temp_path()) << "partial";
    raise(SIGTERM);
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(test::files_in(tmp.path()).empty());
}

namespace {

std::string content(const fs::path& p) { return test::read_bytes(p); }

}  // namespace

// Issue 17: an .h5 and its .xdmf from two different runs. Outputs of one run are committed as a
// unit: when a rename fails, the outputs already renamed are put back.
TEST(AtomicOutput, AUnitIsCommittedWhollyOrNotAtAll) {
  test::TempDir tmp;
  std::ofstream(tmp / "a.h5") << "old a";
  std::ofstream(tmp / "a.xdmf") << "old xdmf";
  {
    OutputUnit unit;
    std::ofstream(unit.add(tmp / "a.h5").temp_path()) << "new a";
    AtomicOutput& sidecar = unit.add(tmp / "a.xdmf");
    std::ofstream(sidecar.temp_path()) << "new xdmf";
    // The second rename fails: its final path became a non-empty folder after the checks.
    fs::remove(tmp / "a.xdmf");
    fs::create_directory(tmp / "a.xdmf");
    std::ofstream(tmp / "a.xdmf" / "keep") << "x";
    EXPECT_THROW(unit.commit(), RuntimeError);
  }
  EXPECT_EQ(content(tmp / "a.h5"), "old a") << "the first output was not put back";
  EXPECT_EQ(test::files_in(tmp.path()), (std::vector<fs::path>{tmp / "a.h5", tmp / "a.xdmf" / "keep"}))
      << "temporary or backup files left behind";
  fs::remove_all(tmp / "a.xdmf");
  {
    OutputUnit unit;
    std::ofstream(unit.add(tmp / "a.h5").temp_path()) << "new a";
    std::ofstream(unit.add(tmp / "a.xdmf").temp_path()) << "new xdmf";
    unit.commit();
  }
  EXPECT_EQ(content(tmp / "a.h5"), "new a");
  EXPECT_EQ(content(tmp / "a.xdmf"), "new xdmf");
  EXPECT_EQ(test::files_in(tmp.path()).size(), 2u);
}

// Two runs writing the same outputs take turns: a commit waits for the folder's lock, so the pair
// it renames cannot interleave with another run's pair.
TEST(AtomicOutput, ConcurrentCommitsIntoOneFolderTakeTurns) {
  test::TempDir tmp;
  OutputUnit unit;
  std::ofstream(unit.add(tmp / "b.h5").temp_path()) << "b";
  std::ofstream(unit.add(tmp / "b.xdmf").temp_path()) << "bx";
  const int fd = ::open(tmp.path().c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);  // another run is committing into this folder
  std::atomic<bool> done{false};
  std::thread committer([&] {
    unit.commit();
    done = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_FALSE(done.load()) << "the commit did not wait for the folder's lock";
  EXPECT_FALSE(fs::exists(tmp / "b.h5"));
  ::flock(fd, LOCK_UN);
  ::close(fd);
  committer.join();
  EXPECT_TRUE(done.load());
  EXPECT_EQ(content(tmp / "b.h5"), "b");
  EXPECT_EQ(content(tmp / "b.xdmf"), "bx");
}

// Issue 17: a FIFO or a 300-character name gave exit 1 with a file system message after the work.
TEST(AtomicOutput, FifosAndOverlongNamesAreRefusedUpFront) {
  test::TempDir tmp;
  ASSERT_EQ(::mkfifo((tmp / "pipe.h5").c_str(), 0600), 0);
  try {
    check_output_path(tmp / "pipe.h5");
    ADD_FAILURE() << "a FIFO was accepted as an output";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("FIFO"), std::string::npos) << e.what();
  }
  const std::string long_name(300, 'n');
  try {
    check_output_path(tmp / (long_name + ".h5"));
    ADD_FAILURE() << "a 300-character name was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("characters"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_output_path(tmp / (std::string(200, 'n') + ".h5")));
}

// Issue 17: `ctsurg-import c.nii.gz c.nii.gz` replaced the CT. An output that is an input, by
// name or by link, is refused, as are two outputs that are one file.
TEST(AtomicOutput, AnOutputThatIsAnInputIsRefused) {
  test::TempDir tmp;
  std::ofstream(tmp / "in.h5") << "input";
  fs::create_symlink(tmp / "in.h5", tmp / "link.h5");
  fs::create_hard_link(tmp / "in.h5", tmp / "hard.h5");
  for (const auto& out : {tmp / "in.h5", tmp / "link.h5", tmp / "hard.h5", tmp / "." / "in.h5"}) {
    EXPECT_THROW(check_output_paths({out}, {tmp / "in.h5"}), InputError) << out;
  }
  EXPECT_THROW(check_output_paths({tmp / "x.h5", tmp / "sub" / ".." / "x.h5"}, {}), InputError);
  fs::create_directory(tmp / "sub");
  EXPECT_THROW(check_output_paths({tmp / "x.h5", tmp / "sub" / ".." / "x.h5"}, {}), InputError);
  EXPECT_NO_THROW(check_output_paths({tmp / "out.h5", tmp / "out.xdmf"}, {tmp / "in.h5", ""}));
}

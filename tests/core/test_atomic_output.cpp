#include "ctsurg/core/atomic_output.h"

#include "ctsurg/core/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>

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

// A process killed by SIGTERM while it writes leaves no temporary when its
// handler unlinks the registered ones (core/io/temporary_files.h), as the
// executable's does (tools/main.cpp). The handler needs the registry in
// static storage: it lives here, as the executable's lives in main.cpp, not
// in the library.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include "core/io/file_util.h"
#include "core/io/temporary_files.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

class TemporariesOnSignal : public testing_fixtures::TempDirTest {};

// The registry of the child below and its handler, as in tools/main.cpp.
TemporaryFiles g_child_temporaries;

extern "C" void UnlinkAndReraise(int sig) {
  g_child_temporaries.UnlinkAll();
  ReraiseWithDefaultAction(sig);
}

// A child writes a large output again and again (nearly all its time inside
// WriteFileAtomically, its temporary registered) until SIGTERM ends it: the
// handler removes the temporary, the output is whole, and the child dies of
// the signal.
TEST_F(TemporariesOnSignal, SigtermDuringAWriteLeavesNoTemporary) {
  const std::string out = Path("big.csv");
  const std::string content(32 << 20, 'x');
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    InstallTerminationHandler(&UnlinkAndReraise);
    WriteOptions options;
    options.temporaries = &g_child_temporaries;
    try {
      for (;;) WriteFileAtomically(out, content, options);
    } catch (...) {
      ::_exit(1);  // never back into the test runner
    }
  }
  for (int i = 0; i < 2000 && !fs::exists(out); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(30));  // into a later write
  ASSERT_EQ(::kill(child, SIGTERM), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  int files = 0;
  for (const fs::directory_entry& e : fs::directory_iterator(dir_)) {
    EXPECT_EQ(e.path().filename().string().rfind(".tmp.", 0), std::string::npos) << e.path();
    ++files;
  }
  EXPECT_EQ(files, 1);
  EXPECT_EQ(fs::file_size(out), content.size());
}

}  // namespace
}  // namespace triadcal

// The output guard (file_util.h) under concurrent readers: `batch` loads its
// units on several threads, each noting its files into the command's guard.
// Before the guard held a mutex, ASan found a heap-buffer-overflow there (two
// threads growing one vector); here many threads note files at once, and the
// guard must still refuse an output that is one of them, in a write too.
#include "core/io/file_util.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "core/model/errors.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

TEST(OutputGuard, ConcurrentReadersAreAllNoted) {
  OutputGuard guard;
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([t, &guard] {
      for (int i = 0; i < 2000; ++i) {
        guard.NoteInput("/nonexistent/guard-test/in_" + std::to_string(t) + "_" +
                        std::to_string(i) + ".csv");
      }
    });
  }
  for (std::thread& th : threads) th.join();
  // The last file of every thread was noted: writing over it is refused.
  for (int t = 0; t < 8; ++t) {
    const std::string in = "/nonexistent/guard-test/in_" + std::to_string(t) + "_1999.csv";
    EXPECT_THROW(guard.CheckOutputsAreNotInputs(in), InputError) << in;
  }
  EXPECT_NO_THROW(guard.CheckOutputsAreNotInputs("/nonexistent/guard-test/out.json"));
  // Another guard is another value.
  const OutputGuard other;
  EXPECT_NO_THROW(other.CheckOutputsAreNotInputs("/nonexistent/guard-test/in_0_1999.csv"));
}

// Inputs: what is wrong with a path that is no readable regular file, in words.
class FileKinds : public testing_fixtures::TempDirTest {};

TEST_F(FileKinds, InputProblems) {
  WriteText("ok.csv", "t\n");
  EXPECT_EQ(InputFileProblem(Path("ok.csv")), "");
  EXPECT_EQ(InputFileProblem(Path("none.csv")), "no such file");
  EXPECT_EQ(InputFileProblem(""), "empty file name");
  std::filesystem::create_directories(Path("dir"));
  EXPECT_EQ(InputFileProblem(Path("dir")), "is a directory, not a file");
  ASSERT_EQ(::mkfifo(Path("fifo").c_str(), 0644), 0);
  EXPECT_EQ(InputFileProblem(Path("fifo")), "is a FIFO (named pipe), not a regular file");
  EXPECT_EQ(InputFileProblem("/dev/null"), "is a device node, not a regular file");
  std::filesystem::create_symlink(Path("b"), Path("a"));
  std::filesystem::create_symlink(Path("a"), Path("b"));
  EXPECT_EQ(InputFileProblem(Path("a")), "too many levels of symbolic links (a symlink loop?)");
  std::filesystem::create_symlink(Path("gone"), Path("dangling"));
  EXPECT_EQ(InputFileProblem(Path("dangling")), "is a symbolic link to a missing file");
  EXPECT_EQ(InputFileProblem(Path(std::string(300, 'n'))),
            "file name too long (longer than the system allows)");
  EXPECT_EQ(InputFileProblem(Path("ok.csv/x")), "a component of the path is not a folder");
  try {
    CheckInputFile(Path("none.csv"));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              Path("none.csv") + ": cannot read (no such file or not readable)");
  }
  try {
    CheckInputFile(Path("fifo"));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              Path("fifo") + ": cannot read: is a FIFO (named pipe), not a regular file");
  }
}

TEST_F(FileKinds, OutputsAreRegularFiles) {
  EXPECT_NO_THROW(CheckOutputFile(Path("new.json")));
  WriteText("old.json", "{}");
  EXPECT_NO_THROW(CheckOutputFile(Path("old.json")));
  std::filesystem::create_symlink(Path("old.json"), Path("link.json"));
  EXPECT_NO_THROW(CheckOutputFile(Path("link.json")));
  ASSERT_EQ(::mkfifo(Path("fifo").c_str(), 0644), 0);
  EXPECT_THROW(CheckOutputFile(Path("fifo")), InputError);
  EXPECT_THROW(CheckOutputFile("/dev/null"), InputError);
  EXPECT_THROW(CheckOutputFile(""), InputError);
  std::filesystem::create_directories(Path("dir"));
  try {
    CheckOutputFile(Path("dir"));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), Path("dir") + ": cannot write: is a directory");
  }
  // Not even a write: WriteFileAtomically refuses them as well.
  EXPECT_THROW(WriteFileAtomically(Path("fifo"), "x"), InputError);
  struct stat st {};
  ASSERT_EQ(::lstat(Path("fifo").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
}

TEST_F(FileKinds, WriteThroughASymlinkKeepsTheLinkAndThePermissions) {
  WriteText("target.txt", "old");
  ::chmod(Path("target.txt").c_str(), 0640);
  std::filesystem::create_symlink(Path("target.txt"), Path("link.txt"));
  WriteFileAtomically(Path("link.txt"), "new");
  EXPECT_TRUE(std::filesystem::is_symlink(Path("link.txt")));
  EXPECT_EQ(ReadFile(Path("target.txt")), "new");
  struct stat st {};
  ASSERT_EQ(::stat(Path("target.txt").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  // Nothing else left in the folder.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir_)) files += !e.path().empty();
  EXPECT_EQ(files, 2);
}

// The guard goes with the write (WriteOptions::guard): an input noted in it is
// never replaced, nor is anything written when an output announced before is
// one; without a guard nothing is checked (a library caller's plain write).
TEST_F(FileKinds, AWriteChecksTheGuardItIsGiven) {
  const std::string in = WriteText("in.csv", "input");
  OutputGuard guard;
  guard.NoteInput(in);
  WriteOptions options;
  options.guard = &guard;
  try {
    WriteFileAtomically(in, "output", options);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), in + ": is the input file '" + in +
                                         "' (an output never replaces an input; choose "
                                         "another name)");
  }
  EXPECT_EQ(ReadFile(in), "input");
  guard.NoteOutput(in);  // announced, as -o is before the work
  EXPECT_THROW(WriteFileAtomically(Path("other.json"), "x", options), InputError);
  EXPECT_FALSE(std::filesystem::exists(Path("other.json")));
  WriteFileAtomically(in, "output");
  EXPECT_EQ(ReadFile(in), "output");
}

TEST_F(FileKinds, TemporaryNamesAndStaleOnes) {
  const std::string tmp = TemporaryPathFor(Path("out.csv"));
  EXPECT_EQ(tmp, Path(".tmp.out.csv." + HostTag() + "." + std::to_string(::getpid())));
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ::waitpid(child, nullptr, 0);
  EXPECT_TRUE(ProcessIsGone(child));
  EXPECT_FALSE(ProcessIsGone(::getpid()));
  const std::string stale = Path(".tmp.out.csv." + HostTag() + "." + std::to_string(child));
  WriteText(".tmp.out.csv." + HostTag() + "." + std::to_string(child), "partial");
  WriteText(".tmp.out.csv.elsewhere." + std::to_string(child), "partial");
  RemoveStaleTemporaries(Path("out.csv"));
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_TRUE(std::filesystem::exists(Path(".tmp.out.csv.elsewhere." + std::to_string(child))));
}

TEST_F(FileKinds, ReadFileRangeIsBounded) {
  WriteText("f.txt", "0123456789");
  EXPECT_EQ(ReadFileRange(Path("f.txt"), 0, 4), "0123");
  EXPECT_EQ(ReadFileRange(Path("f.txt"), 8, 4), "89");
  EXPECT_EQ(ReadFileRange("/dev/zero", 0, 4), "");  // not a regular file: nothing read
  ASSERT_EQ(::mkfifo(Path("fifo").c_str(), 0644), 0);
  EXPECT_EQ(ReadFileRange(Path("fifo"), 0, 4), "");  // and never waited on
}

}  // namespace
}  // namespace triadcal

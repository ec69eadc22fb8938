// The output guard (file_util.h) under concurrent readers: `batch` loads its
// units on several threads, and each reader notes its files. Before the guard
// held a mutex, ASan found a heap-buffer-overflow in NoteInputFile there (two
// threads growing one vector); here many threads note files at once, and the
// guard must still refuse an output that is one of them.
#include "core/io/file_util.h"

#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

#include "core/model/errors.h"

namespace triadcal {
namespace {

TEST(OutputGuard, ConcurrentReadersAreAllNoted) {
  EnableOutputGuard();
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([t] {
      for (int i = 0; i < 2000; ++i) {
        NoteInputFile("/nonexistent/guard-test/in_" + std::to_string(t) + "_" +
                      std::to_string(i) + ".csv");
      }
    });
  }
  for (std::thread& th : threads) th.join();
  // The last file of every thread was noted: writing over it is refused.
  for (int t = 0; t < 8; ++t) {
    const std::string in = "/nonexistent/guard-test/in_" + std::to_string(t) + "_1999.csv";
    EXPECT_THROW(CheckOutputsAreNotInputs(in), InputError) << in;
  }
  EXPECT_NO_THROW(CheckOutputsAreNotInputs("/nonexistent/guard-test/out.json"));
  DisableOutputGuard();
  EXPECT_NO_THROW(CheckOutputsAreNotInputs("/nonexistent/guard-test/in_0_1999.csv"));
}

}  // namespace
}  // namespace triadcal

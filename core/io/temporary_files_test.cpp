// The registry of temporaries (temporary_files.h): fixed slots; only what is
// registered is unlinked. A process killed while it writes:
// tests/temporaries_signal_test.cpp.
#include "core/io/temporary_files.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

class TemporaryFilesTest : public testing_fixtures::TempDirTest {};

TEST_F(TemporaryFilesTest, SlotsAreFixedAndOnlyRegisteredFilesAreUnlinked) {
  TemporaryFiles registry;
  int slots[TemporaryFiles::kSlots];
  for (int i = 0; i < TemporaryFiles::kSlots; ++i) {
    slots[i] = registry.Add(WriteText("t" + std::to_string(i), "x"));
    EXPECT_EQ(slots[i], i);
  }
  EXPECT_EQ(registry.Add(WriteText("extra", "x")), -1);  // full: not known to the handler
  EXPECT_EQ(registry.Add(std::string(TemporaryFiles::kPathBytes, 'a')), -1);  // too long
  registry.Release(slots[3]);
  registry.Release(-1);  // nothing
  registry.UnlinkAll();
  for (int i = 0; i < TemporaryFiles::kSlots; ++i) {
    EXPECT_EQ(fs::exists(Path("t" + std::to_string(i))), i == 3) << i;
  }
  EXPECT_TRUE(fs::exists(Path("extra")));
  EXPECT_EQ(registry.Add(Path("again")), 3);  // a released slot is used again
  {
    const TemporaryRegistration scoped(&registry, WriteText("scoped", "x"));
    const TemporaryRegistration none(nullptr, Path("unregistered"));  // no registry: nothing
  }
  registry.UnlinkAll();
  EXPECT_TRUE(fs::exists(Path("scoped")));  // released when the registration ended
}

}  // namespace
}  // namespace triadcal

// A test fixture with a fresh folder of its own per test (removed afterwards),
// for tests that write files.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace triadcal {
namespace testing_fixtures {

// A folder of this process's own under the temporary folder (name and pid):
// two test runs at once (two checkouts, a sanitizer build) never share it.
inline std::filesystem::path OwnTempDir(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("triadcal_" + name + "_" + std::to_string(::getpid()));
}

class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("triadcal_" + std::string(info->test_suite_name()) + "_" + info->name() + "_" +
            std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string WriteText(const std::string& name, const std::string& text) const {
    std::ofstream(Path(name), std::ios::binary) << text;
    return Path(name);
  }

  std::filesystem::path dir_;
};

}  // namespace testing_fixtures
}  // namespace triadcal

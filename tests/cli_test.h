// A fixture for tests that run the built `triadcal` (TRIADCAL_BIN) in a
// fresh folder of their own, on a small simulated run of the paper's profile
// (run.csv, run.yaml with `data: run.csv`): Run gives its exit code and
// stderr, ExpectError the exact one-line error of bad input.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/simulation/simulator.h"
#include "tests/sim_fixtures.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace testing_fixtures {

struct CliResult {
  int exit_code = -1;
  std::string err;
};

// An OUT as a test compares it: through its text (as written), without
// what changes from run to run (the provenance, the time taken).
inline nlohmann::json Comparable(const nlohmann::json& out) {
  nlohmann::json j = nlohmann::json::parse(out.dump());
  j.erase("provenance");
  j.erase("time_s");
  return j;
}

class CliTest : public TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    const Scenario s = PaperScenario(50.0, 20.0, 2.0, 15.0, 11);
    WriteRunCsv(Simulate(s), Path("run.csv"), "");
    WriteText("run.yaml", "data: run.csv\n");
  }

  // `ENV triadcal ARGS`, stdout discarded.
  CliResult Run(const std::string& args, const std::string& env = "") const {
    const std::string err = Path("stderr.txt");
    const int status = std::system(
        (env + " " + std::string(TRIADCAL_BIN) + " " + args + " > /dev/null 2> " + err).c_str());
    CliResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err = ReadFile(err);
    return r;
  }

  // The OUT a command wrote into this test's folder, Comparable.
  nlohmann::json Out(const std::string& name) const {
    return Comparable(nlohmann::json::parse(ReadFile(Path(name))));
  }

  // `triadcal ARGS` must fail with exit 2 and exactly "triadcal: error: WHAT\n",
  // and leave none of the files named in `outputs`.
  void ExpectError(const std::string& args, const std::string& what,
                   const std::vector<std::string>& outputs = {"out.json"}) const {
    const CliResult r = Run(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err, "triadcal: error: " + what + "\n") << args;
    for (const std::string& o : outputs) {
      EXPECT_FALSE(std::filesystem::exists(Path(o))) << o << ": " << args;
    }
  }
};

}  // namespace testing_fixtures
}  // namespace triadcal

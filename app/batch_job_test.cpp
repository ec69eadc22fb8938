// The batch job (app/batch_job.h): one Validate naming the option, the same
// files as `triadcal batch`, and limits judged in the unit of each run's own
// fit (counts/g for readings in counts).
#include "app/batch_job.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tests/cli_test.h"
#include "tests/error_of.h"

namespace triadcal {
namespace {

using testing_fixtures::ValidateError;

namespace fs = std::filesystem;
using testing_fixtures::Comparable;

TEST(BatchSettings, ValidateNamesTheOption) {
  EXPECT_EQ(ValidateError(BatchSettings()), "");
  BatchSettings s;
  s.date = "2026-13-01";
  EXPECT_EQ(ValidateError(s), "--date: expected YYYY-MM-DD, got '2026-13-01'");
  s = BatchSettings();
  s.shard = {3, 2};
  EXPECT_EQ(ValidateError(s), "--shard: expected I/N with 1 <= I <= N, got '3/2'");
  s = BatchSettings();
  s.threads = -1;
  EXPECT_EQ(ValidateError(s), "--threads: Value -1 not in range 0 to 1024");
  s = BatchSettings();
  s.fit.hold = {"Kx"};
  s.fit.free = {"Kx"};
  EXPECT_EQ(ValidateError(s), "--hold/--free: 'Kx' given to both: hold it or free it");
}

class BatchJob : public testing_fixtures::CliTest {
 protected:
  // The single summary_*.json written in `dir`.
  nlohmann::json Summary(const std::string& dir) const {
    std::string found;
    for (const auto& e : fs::directory_iterator(Path(dir))) {
      const std::string name = e.path().filename().string();
      if (name.rfind("summary_", 0) == 0 && e.path().extension() == ".json") found = e.path();
    }
    EXPECT_FALSE(found.empty()) << dir;
    nlohmann::json j = Comparable(nlohmann::json::parse(ReadFile(found)));
    j.erase("execution");
    j.erase("output_dir");
    for (nlohmann::json& r : j["results"]) r.erase("time_s");
    return j;
  }
};

// The run in mV and the same numbers read as counts: each judged in its own
// fit's unit. The job files what the command files.
TEST_F(BatchJob, SameFilesAsTheCommandLine) {
  WriteText("counts.yaml",
            "data: run.csv\ntriad: {bias_mV: [1500, 1500, 1500]}\ncolumns:\n"
            "  wx: {source: wx, unit: counts, counts_per_g: 174}\n"
            "  wy: {source: wy, unit: counts, counts_per_g: 174}\n"
            "  wz: {source: wz, unit: counts, counts_per_g: 174}\n");
  const std::string manifest =
      WriteText("m.csv", "serial,run,Kx_max\nM1,run.yaml,185\nC1,counts.yaml,170\nX1,none.yaml,\n");
  const testing_fixtures::CliResult cli =
      Run("batch " + manifest + " -o " + Path("cli") + " --date 2026-01-31");
  ASSERT_EQ(cli.exit_code, 0) << cli.err;

  BatchSettings s;
  s.date = "2026-01-31";
  s.threads = 1;
  Session session;
  const BatchOutcome o =
      BatchRun(s, manifest, LoadManifest(manifest), Path("job"), BatchRanks(), session);
  ASSERT_TRUE(o.filed);
  ASSERT_EQ(o.units.size(), 3u);
  EXPECT_EQ(o.units[0].status, "pass");
  EXPECT_EQ(o.units[1].status, "fail");
  ASSERT_EQ(o.units[1].violations.size(), 1u);
  EXPECT_EQ(o.units[1].violations[0].unit, "counts/g");
  EXPECT_EQ(o.units[1].reason.rfind("outside limits: Kx 171.", 0), 0u) << o.units[1].reason;
  EXPECT_NE(o.units[1].reason.find(" > max 170 counts/g"), std::string::npos) << o.units[1].reason;
  EXPECT_EQ(o.units[2].status, "error");

  EXPECT_EQ(Summary("job"), Summary("cli"));
  for (const char* serial : {"M1", "C1"}) {
    for (const char* file : {"calibration.json", "unit.json"}) {
      const std::string name = std::string(serial) + "/2026-01-31/" + file;
      EXPECT_EQ(Out("job/" + name), Out("cli/" + name)) << name;
    }
  }
}

}  // namespace
}  // namespace triadcal

// The static job (app/static_job.h): the reference both ways, one Validate
// naming the option, and the same OUT as `triadcal static` on six labelled
// positions.
#include "app/static_job.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <string>

#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tests/cli_test.h"
#include "tests/error_of.h"

namespace triadcal {
namespace {

using testing_fixtures::ValidateError;

TEST(StaticSettings, ReferenceBothWays) {
  EXPECT_EQ(ParseStaticReference("auto"), std::nullopt);
  for (StaticReference r :
       {StaticReference::kAngles, StaticReference::kLabels, StaticReference::kNone}) {
    EXPECT_EQ(ParseStaticReference(StaticReferenceName(r)), r);
  }
  EXPECT_EQ(std::string(StaticReferenceName(StaticSettings().reference)), "auto");
  try {
    ParseStaticReference("sideways");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--reference: expected auto, angles, labels or none, got 'sideways'");
  }
}

TEST(StaticSettings, ValidateNamesTheOption) {
  EXPECT_EQ(ValidateError(StaticSettings()), "");
  StaticSettings s;
  s.placement_sigma_deg = 50.0;
  EXPECT_EQ(ValidateError(s), "--placement-sigma-deg: must be at most 45");
  s = StaticSettings();
  s.placement_sigma_deg = -1.0;
  EXPECT_EQ(ValidateError(s), "--placement-sigma-deg: must be >= 0");
  s = StaticSettings();
  s.still.noise_factor = 0.0;
  EXPECT_EQ(ValidateError(s), "--noise-factor: must be > 0");
  s = StaticSettings();
  s.still.min_still_s = 1e4;
  EXPECT_EQ(ValidateError(s), "--min-still-s: must be at most 3600 s");
}

class StaticJob : public testing_fixtures::TempDirTest {
 protected:
  // Six labelled holds of 3 s at 100 Hz (the Ferraris convention), a triad
  // of 2048 counts/g and zero offset with 7 counts of noise.
  void SetUp() override {
    TempDirTest::SetUp();
    std::mt19937_64 rng(5);
    std::normal_distribution<double> noise(0.0, 7.0);
    std::string csv = "t,acc_x,acc_y,acc_z,part\n";
    int k = 0;
    for (const auto& [label, up] : DefaultLabelPositions()) {
      for (int j = 0; j < 300; ++j, ++k) {
        csv += FormatDouble(0.01 * k);
        for (int i = 0; i < 3; ++i) csv += "," + FormatDouble(2048.0 * up[i] + noise(rng));
        csv += "," + label + "\n";
      }
    }
    WriteText("s.csv", csv);
    run_yaml_ =
        WriteText("run.yaml",
                  "data: s.csv\n"
                  "columns: {t: t, lambda1: {value: 0}, lambda2: {value: 0}, wx: acc_x, wy: acc_y, "
                  "wz: acc_z, label: part}\n"
                  "triad: {scale_mV_per_g: [2048, 2048, 2048], bias_mV: [0, 0, 0], noise_mV: 7}\n");
  }
  std::string run_yaml_;
};

TEST_F(StaticJob, SameOutAsTheCommandLine) {
  const std::string cmd = std::string(TRIADCAL_BIN) + " static " + run_yaml_ +
                          " --fix Kxy --placement-sigma-deg 0.2 -o " + Path("out.json") +
                          " > /dev/null 2> " + Path("err.txt");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadFile(Path("err.txt"));
  Session session;
  const LoadedRun run = LoadRun(run_yaml_, &session);
  StaticSettings s;
  s.fix = {"Kxy"};
  s.placement_sigma_deg = 0.2;
  const StaticOutcome o = StaticRun(s, run_yaml_, run, session);
  EXPECT_EQ(o.json["reference"], "labels");
  EXPECT_EQ(o.json["positions"].size(), 6u);
  EXPECT_EQ(testing_fixtures::Comparable(o.json),
            testing_fixtures::Comparable(nlohmann::json::parse(ReadFile(Path("out.json")))));
  // A reference the run does not have: the option, then the run's problem.
  s.reference = StaticReference::kAngles;
  try {
    StaticRun(s, run_yaml_, run, session);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--reference angles: " + run_yaml_ +
                  ": columns.lambda1/lambda2 are constants: no bench angles in this run");
  }
}

}  // namespace
}  // namespace triadcal

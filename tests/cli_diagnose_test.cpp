// `triadcal diagnose` OUT: a refitted candidate carries its Wald test beside
// the likelihood ratio (docs/file-formats.md), a score-only one does not, and
// the printed ranking shows the Wald p-value.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/io/file_util.h"
#include "tests/cli_scenarios.h"
#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

using testing_fixtures::RunTriadcal;

class DiagnoseCli : public testing_fixtures::TempDirTest {};

// A 2-ms latency on the paper profile (white noise): selected, with the Wald
// statistic within 20 % of the likelihood ratio and the model's covariance
// behind it (wald_dof null: chi-square reference).
TEST_F(DiagnoseCli, RefittedCandidateCarriesItsWaldTest) {
  const std::string sc =
      WriteText("scenario.yaml", std::string(testing_fixtures::kPaper60sScenario) +
                                     "effects:\n  angle_latency: {tau_ms: 2.0}\n");
  ASSERT_EQ(
      RunTriadcal("simulate " + sc + " -o " + Path("sim") + " --seed 2", Path("s.err")).status, 0);
  // stdout kept (RunCommand discards the subshell's, not the command's).
  const auto r = testing_fixtures::RunCommand(
      std::string("(") + TRIADCAL_BIN + " diagnose " + Path("sim/run.yaml") + " -o " +
          Path("d.json") + " --candidates angle_latency,thermal_drift,scale_asymmetry > " +
          Path("d.txt") + ")",
      Path("d.err"));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json d = nlohmann::json::parse(ReadFile(Path("d.json")));
  ASSERT_EQ(d["selected"], nlohmann::json::array({"angle_latency"})) << d["selected"];
  int refitted = 0, score_only = 0;
  for (const nlohmann::json& t : d["ranking"]) {
    if (t["refit"].get<bool>()) {
      ++refitted;
      ASSERT_TRUE(t.contains("wald")) << t;
      EXPECT_TRUE(t["wald_dof"].is_null()) << t;  // white residual: the model's covariance
      if (t["effect"] == "angle_latency") {
        EXPECT_LT(t["wald_p_value"].get<double>(), t["threshold"].get<double>());
        EXPECT_NEAR(t["wald"].get<double>() / t["statistic"].get<double>(), 1.0, 0.2) << t;
      }
    } else {
      ++score_only;
      EXPECT_FALSE(t.contains("wald")) << t;
    }
  }
  EXPECT_GE(refitted, 1);
  EXPECT_GE(score_only, 1);
  const std::string text = ReadFile(Path("d.txt"));
  EXPECT_NE(text.find("Wald p"), std::string::npos) << text;
}

}  // namespace
}  // namespace triadcal

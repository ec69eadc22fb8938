// `triadcal diagnose` OUT: a refitted candidate carries its Wald test beside
// the likelihood ratio (docs/file-formats.md), a score-only one does not, one
// judged on its one-step estimate carries no refit's figures, and the
// printed ranking shows the Wald p-value.
#include <gtest/gtest.h>

#include <cmath>

#include <nlohmann/json.hpp>
#include <string>

#include "core/io/file_util.h"
#include "tests/cli_scenarios.h"
#include "tests/command_runner.h"
#include "tests/cli_test.h"
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
      // Only one kept from its refit by its one-step Wald test has one.
      EXPECT_EQ(t.contains("wald"), t["one_step_wald"].get<bool>()) << t;
    }
  }
  EXPECT_GE(refitted, 1);
  EXPECT_GE(score_only, 1);
  const std::string text = ReadFile(Path("d.txt"));
  EXPECT_NE(text.find("Wald p"), std::string::npos) << text;
}

// The inner axis 35 mm from the outer one (plausible within 20 mm): judged on
// its one-step estimate, not refitted. Its "absorbing" entry says so
// ("refit" false) and carries no refit's chi2/dof (null, not 0); its test in
// "tests" has no likelihood ratio.
TEST_F(DiagnoseCli, CandidateJudgedOnItsOneStepEstimateCarriesNoRefitFigures) {
  const std::string sc =
      WriteText("scenario.yaml", std::string(testing_fixtures::kPaper60sScenario) +
                                     "effects:\n  axis_nonintersection: {d_mm: 35.0}\n");
  ASSERT_EQ(
      RunTriadcal("simulate " + sc + " -o " + Path("sim") + " --seed 3", Path("s.err")).status, 0);
  ASSERT_EQ(RunTriadcal("diagnose " + Path("sim/run.yaml") + " -o " + Path("d.json") +
                            " --candidates axis_nonintersection,thermal_drift --max-effects 1",
                        Path("d.err"))
                .status,
            0);
  const nlohmann::json d = nlohmann::json::parse(ReadFile(Path("d.json")));
  ASSERT_EQ(d["absorbing"].size(), 1u) << d["absorbing"];
  const nlohmann::json& a = d["absorbing"][0];
  EXPECT_EQ(a["effect"], "axis_nonintersection");
  EXPECT_FALSE(a["refit"].get<bool>()) << a;
  EXPECT_TRUE(a["chi2_per_dof_after"].is_null()) << a;
  EXPECT_NE(a["absorbs"].get<std::string>().find("(one-step estimate, not refitted)"),
            std::string::npos)
      << a;
  bool seen = false;
  for (const nlohmann::json& t : d["tests"]) {
    if (t["effect"] != "axis_nonintersection") continue;
    seen = true;
    EXPECT_FALSE(t["refit"].get<bool>()) << t;
    EXPECT_TRUE(t["likelihood_ratio"].is_null()) << t;
    EXPECT_FALSE(t.contains("wald")) << t;
  }
  EXPECT_TRUE(seen);
}

// diagnose takes --rate-window-s as fit does: with the loop off (--max-effects
// 0) its "before" is fit's at the same window, and not the default window's;
// a window out of range is the option's one-line error.
class DiagnoseRateWindow : public testing_fixtures::CliTest {};

TEST_F(DiagnoseRateWindow, ReachesTheFits) {
  const std::string run = Path("run.yaml");
  ASSERT_EQ(Run("fit " + run + " --rate-window-s 0.03 -o " + Path("fit.json")).exit_code, 0);
  ASSERT_EQ(Run("fit " + run + " -o " + Path("fit_default.json")).exit_code, 0);
  const testing_fixtures::CliResult d =
      Run("diagnose " + run + " --max-effects 0 --rate-window-s 0.03 -o " + Path("d.json"));
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const nlohmann::json fit = Out("fit.json"), other = Out("fit_default.json"), diag = Out("d.json");
  for (const char* name : {"Kx", "alpha_y", "dpsi", "dx2"}) {
    SCOPED_TRACE(name);
    const double f = fit["parameters"][name]["value"], o = other["parameters"][name]["value"];
    const double b = diag["before"]["parameters"][name]["value"];
    EXPECT_NEAR(b, f, 1e-9 * (1.0 + std::abs(f)));
    EXPECT_NE(b, o);
  }
  ExpectError("diagnose " + run + " --rate-window-s 5 -o " + Path("out.json"),
              "--rate-window-s: Value 5 not in range 0.001000 to 2.000000 (see `triadcal diagnose "
              "--help`)");
}

// diagnose takes --threads as fit does (loading, passes, reductions): on one
// thread the same diagnosis, number for number; out of range, the option's
// one-line error.
class DiagnoseThreads : public testing_fixtures::CliTest {};

TEST_F(DiagnoseThreads, OneThreadGivesTheSameDiagnosis) {
  const std::string run = Path("run.yaml");
  const std::string common = " --candidates thermal_drift,angle_latency --max-effects 1 -o ";
  ASSERT_EQ(Run("diagnose " + run + common + Path("all.json")).exit_code, 0);
  const testing_fixtures::CliResult one =
      Run("diagnose " + run + " --threads 1" + common + Path("one.json"));
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_EQ(Out("one.json"), Out("all.json"));
  ExpectError("diagnose " + run + " --threads -1 -o " + Path("out.json"),
              "--threads: Value -1 not in range 0 to 1024 (see `triadcal diagnose --help`)");
}

}  // namespace
}  // namespace triadcal

// `triadcal diagnose` OUT: a refitted candidate carries its Wald test beside
// the likelihood ratio (docs/file-formats.md), a score-only one does not, and
// the printed ranking shows the Wald p-value.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/io/file_util.h"
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
  const std::string sc = WriteText("scenario.yaml", R"(
profile: {duration_s: 60, rate_hz: 50}
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3,
        dpsi: -33, dtheta_c: 43, dlambda2: -33, dx2: -7, dy2: 16, dz2: 4}
noise: {accel_mV: 2.0, angle_arcsec: 15}
run:
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
effects:
  angle_latency: {tau_ms: 2.0}
)");
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

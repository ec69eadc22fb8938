// `triadcal fit` and its sigma at the command line (docs/file-formats.md):
// on a run whose reading noise is correlated in time, OUT says the sigma is
// the HAC one and carries both; `--sigma white` forces the model's; a bad
// `--sigma` is a one-line error with no output file.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::RunTriadcal;

class SigmaCli : public testing_fixtures::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    const std::string scenario = WriteText("coloured.yaml", R"(
profile: {duration_s: 60, rate_hz: 50}
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3,
        dpsi: -33, dtheta_c: 43, dlambda2: -33, dx2: -7, dy2: 16, dz2: 4}
noise: {accel_mV: 2.0, angle_arcsec: 15, accel_correlation_s: 0.5}
run:
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
)");
    const auto r = RunTriadcal("simulate " + scenario + " -o " + Path("run") + " --seed 4",
                               Path("sim.err"));
    ASSERT_EQ(r.status, 0) << r.err;
  }
  nlohmann::json Fit(const std::string& extra) {
    const auto r = RunTriadcal("fit " + Path("run/run.yaml") + " -o " + Path("out.json") +
                                   " --force -q " + extra,
                               Path("fit.err"));
    EXPECT_EQ(r.status, 0) << r.err;
    std::ifstream in(Path("out.json"));
    return nlohmann::json::parse(in);
  }
};

TEST_F(SigmaCli, CorrelatedResidualsGiveTheHacSigmaAndBoth) {
  const nlohmann::json out = Fit("");
  EXPECT_FALSE(out["verdict"]["residual_white"].get<bool>());
  EXPECT_EQ(out["sigma_method"], "hac");
  EXPECT_EQ(out["hac"]["kernel"], "Bartlett");
  EXPECT_GT(out["hac"]["bandwidth_epochs"].get<double>(), 0.0);
  EXPECT_EQ(out["hac"]["kernel_bias_correction"], "AR(1) ratio per parameter");
  EXPECT_GT(out["hac"]["kernel_bias_sigma_factor_max"].get<double>(), 1.0);
  EXPECT_NE(out["verdict"]["sentence"].get<std::string>().find("sigma from the HAC covariance"),
            std::string::npos);
  int larger = 0;
  for (const auto& [name, p] : out["parameters"].items()) {
    if (p["sigma"].is_null()) continue;
    const double s = p["sigma"], w = p["sigma_white"], h = p["sigma_hac"];
    EXPECT_GE(s, w * (1 - 1e-9)) << name;
    EXPECT_DOUBLE_EQ(s, std::max(w, h)) << name;
    if (h > 1.2 * w) ++larger;
  }
  EXPECT_GT(larger, 10);  // the correlation shows in most parameters

  const nlohmann::json white = Fit("--sigma white");
  EXPECT_EQ(white["sigma_method"], "white");
  EXPECT_FALSE(white["hac"].contains("floor"));
  for (const auto& [name, p] : white["parameters"].items()) {
    if (!p["sigma"].is_null()) {
      EXPECT_DOUBLE_EQ(p["sigma"], p["sigma_white"]) << name;
    }
  }
}

TEST_F(SigmaCli, UnknownSigmaMethodIsOneLineWithoutOutput) {
  const auto r = RunTriadcal("fit " + Path("run/run.yaml") + " -o " + Path("out.json") +
                                 " --sigma sandwich",
                             Path("fit.err"));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("--sigma"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("sandwich"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

}  // namespace
}  // namespace triadcal

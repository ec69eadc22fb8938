// The gyro triad's input at the command line (SPEC section 10): each bad gyro
// input gives exit 2, exactly one line on stderr and no output file; gyro
// columns without a gyro block give one warning line and the fit of the
// accelerometer as before. The runs are the fixture's simulated paper run,
// here with a gyro.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "tests/cli_test.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

class CliGyroInput : public testing_fixtures::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();  // run.csv without a gyro, run.yaml
    // gyro.csv: the same paper run with a nominal gyro (0.05 deg/s noise).
    Scenario s = testing_fixtures::PaperScenario(50.0, 20.0, 2.0, 15.0, 11);
    s.run.gyro = GyroDescription{};
    s.truth_layout = ParameterLayout({}, /*gyro=*/true);
    Eigen::VectorXd theta = NominalTheta(s.run, s.truth_layout);
    theta.head(kNumBaseParams) = s.truth;
    s.truth = theta;
    gyro_run_ = Simulate(s);
    WriteRunCsv(gyro_run_, Path("gyro.csv"), "");
  }

  std::string Fit(const std::string& yaml_text) const {
    return "fit " + WriteText("bad.yaml", yaml_text) + " -o " + Path("out.json");
  }

  RunData gyro_run_;
};

TEST_F(CliGyroInput, GyroBlockWithoutGyroColumns) {
  ExpectError(Fit("data: run.csv\ngyro: {}\n"),
              Path("run.csv") +
                  ":1: missing gyro columns 'gx', 'gy', 'gz' (run.yaml has a gyro block: give gx, "
                  "gy and gz, or remove the block; header: t, lambda1, lambda2, wx, wy, wz)");
}

TEST_F(CliGyroInput, BadGyroBlockAndBenchLocation) {
  const std::string y = Path("bad.yaml");
  ExpectError(Fit("data: gyro.csv\ngyro: {scale: [1, 0, 1]}\n"),
              y + ": gyro.scale[1]: must not be 0 (readings per deg/s; nominal 1)");
  ExpectError(Fit("data: gyro.csv\ngyro: {noise_dps: 0}\n"),
              y + ": gyro.noise_dps: must be > 0, got 0");
  ExpectError(Fit("data: gyro.csv\nbench: {latitude_deg: 48}\ngyro: {}\n"),
              y + ": bench.latitude_deg: given without bench.heading_deg (Earth's rate needs both; "
                  "give both, or neither)");
  ExpectError(Fit("data: gyro.csv\nbench: {latitude_deg: -91, heading_deg: 0}\ngyro: {}\n"),
              y + ": bench.latitude_deg: must be within [-90, 90] deg, got -91");
}

TEST_F(CliGyroInput, NonFiniteGyroReading) {
  RunData d = gyro_run_;
  d.gyro_rad_s[1][7] = std::nan("");
  WriteRunCsv(d, Path("gyro.csv"), "");
  ExpectError(Fit("data: gyro.csv\ngyro: {}\n"),
              Path("gyro.csv") + ":9: column 'gy': NaN (every sample must be a number)");
}

TEST_F(CliGyroInput, RadiansPerSecondDeclaredAsDegreesPerSecond) {
  RunData d = gyro_run_;
  for (auto& g : d.gyro_rad_s) {
    for (double& v : g) v *= kDegToRad;  // run.csv then holds the rad/s numbers
  }
  WriteRunCsv(d, Path("gyro.csv"), "");
  const testing_fixtures::CliResult r = Run(Fit("data: gyro.csv\ngyro: {}\n"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::string head =
      "triadcal: error: " + Path("gyro.csv") +
      ": column 'gx', column 'gy', column 'gz': the RMS of |g| over the run is ";
  const std::string tail =
      ": the gyro readings look like rad/s, not deg/s; declare `unit: rad/s` (columns.gx, gy, "
      "gz)\n";
  EXPECT_EQ(r.err.rfind(head, 0), 0u) << r.err;
  ASSERT_GE(r.err.size(), tail.size());
  EXPECT_EQ(r.err.substr(r.err.size() - tail.size()), tail) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(Path("out.json")));
}

// Not a bad input: the accelerometer is fitted as before, with one warning.
TEST_F(CliGyroInput, GyroColumnsWithoutAGyroBlockWarnOnce) {
  const testing_fixtures::CliResult r = Run(Fit("data: gyro.csv\n"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err,
            "triadcal: warning: gx gy gz present but run.yaml has no gyro block: the gyro is not "
            "calibrated\n");
  EXPECT_TRUE(std::filesystem::exists(Path("out.json")));
}

}  // namespace
}  // namespace triadcal

// Progress on stderr: when piped, whole lines (no carriage returns) whose
// percentage climbs to near the end for fit, compare and diagnose; nothing
// with --quiet. TRIADCAL_PROGRESS_INTERVAL_S=0 prints every update, so the
// test does not depend on how long the commands take.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

const char* kScenario = R"(
seed: 3
profile: {amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0], duration_s: 30, rate_hz: 25}
truth: {Kx: 171.5, W0x: 1504.2, gamma_y: 140, dpsi: -33, dlambda2: -33, dx2: -7}
noise: {accel_mV: 2.0, angle_arcsec: 15}
run:
  bench: {lever_arm_mm: [138, 20, 20]}
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
)";

class ProgressTest : public testing_fixtures::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    WriteText("scen.yaml", kScenario);
    ASSERT_EQ(Run("simulate " + Path("scen.yaml") + " -o " + Path("sim")), 0) << Err();
  }
  int Run(const std::string& args, const std::string& env = "") const {
    return std::system((env + " " + std::string(TRIADCAL_BIN) + " " + args + " > " +
                        Path("out.txt") + " 2> " + Path("err.txt"))
                           .c_str());
  }
  std::string Err() const {
    std::ifstream f(Path("err.txt"), std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }
  // The percentages of the lines that start with `prefix`.
  std::vector<int> Percentages(const std::string& prefix) const {
    std::vector<int> out;
    std::istringstream in(Err());
    const std::regex line("^" + prefix + ": .* +([0-9]+)%$");
    for (std::string l; std::getline(in, l);) {
      std::smatch m;
      EXPECT_TRUE(std::regex_match(l, m, line)) << "not a progress line: '" << l << "'";
      if (m.size() == 2) out.push_back(std::stoi(m[1]));
    }
    return out;
  }
  void ExpectClimbs(const std::vector<int>& pct, int at_least) const {
    ASSERT_FALSE(pct.empty()) << Err();
    for (std::size_t i = 1; i < pct.size(); ++i) EXPECT_GE(pct[i], pct[i - 1]) << Err();
    EXPECT_EQ(pct.front(), 0);
    EXPECT_GE(pct.back(), at_least) << Err();
    EXPECT_LE(pct.back(), 100);
  }
};

const char* kEveryUpdate = "TRIADCAL_PROGRESS_INTERVAL_S=0";

TEST_F(ProgressTest, FitReportsClimbingFractionsInWholeLines) {
  ASSERT_EQ(Run("fit " + Path("sim/run.yaml") + " -o " + Path("f.json"), kEveryUpdate), 0) << Err();
  EXPECT_EQ(Err().find('\r'), std::string::npos);
  ExpectClimbs(Percentages("fit"), 100);
}

TEST_F(ProgressTest, CompareCoversFilterThenBatch) {
  ASSERT_EQ(Run("compare " + Path("sim/run.yaml") + " -o " + Path("c.json"), kEveryUpdate), 0)
      << Err();
  const std::vector<int> pct = Percentages("compare");
  ExpectClimbs(pct, 100);
  EXPECT_NE(Err().find("compare: filter pass 2"), std::string::npos);
  EXPECT_NE(Err().find("compare: fit step 1: "), std::string::npos);
}

TEST_F(ProgressTest, DiagnoseMovesThroughTheCandidateFits) {
  ASSERT_EQ(Run("diagnose " + Path("sim/run.yaml") + " -o " + Path("d.json") +
                    " --candidates angle_latency,thermal_drift",
                kEveryUpdate),
            0)
      << Err();
  const std::vector<int> pct = Percentages("diagnose");
  ExpectClimbs(pct, 95);
  // Candidates are scored first (no refit), then only the close ones refitted.
  EXPECT_NE(Err().find("diagnose: round 1: score tests of 2 candidates"), std::string::npos);
}

TEST_F(ProgressTest, QuietPrintsNothing) {
  ASSERT_EQ(Run("fit " + Path("sim/run.yaml") + " -o " + Path("f.json") + " --quiet", kEveryUpdate),
            0);
  EXPECT_EQ(Err(), "");
  ASSERT_EQ(Run("diagnose " + Path("sim/run.yaml") + " -o " + Path("d.json") +
                    " -q --candidates angle_latency",
                kEveryUpdate),
            0);
  EXPECT_EQ(Err(), "");
}

}  // namespace
}  // namespace triadcal

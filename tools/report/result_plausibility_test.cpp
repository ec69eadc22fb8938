// Implausible results: a warning per parameter beyond its bound, naming the
// likely cause; nothing for plausible, held or not estimable parameters.
#include "tools/report/result_plausibility.h"

#include <gtest/gtest.h>

namespace triadcal {
namespace {

nlohmann::json Entry(double value, const char* unit) { return {{"value", value}, {"unit", unit}}; }

TEST(ResultPlausibility, GammaFarBeyondAMemsTriadNamesTheInnerZero) {
  nlohmann::json p;
  p["gamma_y"] = Entry(442.0, "arcmin");
  p["gamma_z"] = Entry(64.0, "arcmin");  // the paper's: plausible
  p["Kx"] = Entry(171.5, "mV/g");
  const std::vector<std::string> w = ImplausibleResultWarnings(p, "out.json");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0],
            "out.json: parameters.gamma_y = 442 arcmin (7.37 deg) is beyond what a triad's axes "
            "can be off (3 deg): likely an inner angle-sensor zero (columns.lambda2.offset) held "
            "by a levelling constraint (dpsi - dlambda2) that does not hold for this bench, or a "
            "wrong mounting; a result this far outside the plausible is no calibration");
}

TEST(ResultPlausibility, BenchAnglesAndLeverArm) {
  nlohmann::json p;
  p["dtheta_c"] = Entry(-400.0, "arcmin");
  p["dx2"] = Entry(250.0, "mm");
  p["dy2"] = Entry(16.0, "mm");
  const std::vector<std::string> w = ImplausibleResultWarnings(p, "o.json");
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0],
            "o.json: parameters.dtheta_c = -400 arcmin (-6.67 deg) is beyond what a levelled "
            "bench can be off (5 deg): likely an outer angle-sensor zero "
            "(columns.lambda1.offset); a result this far outside the plausible is no calibration");
  EXPECT_EQ(w[1],
            "o.json: parameters.dx2 = 250 mm is beyond what the lever arm can differ from the "
            "drawings (150 mm): likely a wrong bench.lever_arm_mm (R0), or the readings' axes "
            "mapped wrongly; a result this far outside the plausible is no calibration");
}

TEST(ResultPlausibility, HeldOrNotEstimableParametersAreNotJudged) {
  nlohmann::json p;
  p["gamma_y"] = Entry(900.0, "arcmin");
  p["gamma_y"]["held"] = true;
  p["beta_x"] = Entry(900.0, "arcmin");
  p["beta_x"]["estimable"] = false;
  p["alpha_x"] = Entry(900.0, "arcmin");
  p["alpha_x"]["held"] = "no bench";
  EXPECT_TRUE(ImplausibleResultWarnings(p, "o.json").empty());
  EXPECT_TRUE(ImplausibleResultWarnings(nlohmann::json(), "o.json").empty());
}

}  // namespace
}  // namespace triadcal

// The design job (app/design_job.h): the text forms both ways, one Validate
// naming the option, and the same OUT as `triadcal design`.
#include "app/design_job.h"

#include <gtest/gtest.h>

#include <string>

#include "core/model/errors.h"
#include "tests/cli_test.h"
#include "tests/error_of.h"

namespace triadcal {
namespace {

using testing_fixtures::Comparable;

using testing_fixtures::ErrorOf;

TEST(DesignSettings, TextBothWays) {
  const DesignSettings d;
  EXPECT_EQ(ListText(d.durations_s), "15,30,60,90,300,600,2400");
  EXPECT_EQ(TargetsText(d.targets), "K=0.5");
  EXPECT_EQ(ParsePositiveList(ListText(d.durations_s), "--durations"), d.durations_s);
  const std::vector<DesignTarget> t = ParseDesignTargets("K=0.5, W0=2");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(TargetsText(t), "K=0.5,W0=2");
  EXPECT_EQ(ParsePairs("30:12,60:24", "--periods")[1][1], 24.0);
  EXPECT_EQ(ErrorOf([] { ParsePairs("30", "--periods"); }),
            "--periods: expected OUTER:INNER pairs such as 30:12, got '30'");
  EXPECT_EQ(ErrorOf([] { ParseDesignTargets("K"); }),
            "--target: expected NAME=SIGMA (file units) such as K=0.5, got 'K'");
  EXPECT_EQ(ErrorOf([] { ParsePositiveList("15,-1", "--durations"); }),
            "--durations: expected a positive number, got '-1'");
}

TEST(DesignSettings, ValidateNamesTheOption) {
  EXPECT_EQ(ErrorOf([] { DesignSettings().Validate(); }), "");
  DesignSettings s;
  s.static_positions = 7;
  EXPECT_EQ(ErrorOf([&] { s.Validate(); }), "--static-positions: expected 6, 12 or 18, got 7");
  s = DesignSettings();
  s.targets = ParseDesignTargets("K=2,Q=1");
  EXPECT_EQ(ErrorOf([&] { s.Validate(); }),
            "--target: unknown parameter or group 'Q' (a parameter name or K, W0, angles, K_ij, "
            "bench, dR)");
  s = DesignSettings();
  s.durations_s = {};
  EXPECT_EQ(ErrorOf([&] { s.Validate(); }),
            "--durations: expected a comma-separated list, got nothing");
}

class DesignJob : public testing_fixtures::CliTest {};

TEST_F(DesignJob, SameOutAsTheCommandLine) {
  const std::string scenario = WriteText(
      "scenario.yaml",
      "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 20, rate_hz: 25}\n"
      "truth: {Kx: 171.5, W0x: 1504.2}\n"
      "noise: {accel_mV: 2, angle_arcsec: 15}\n");
  const testing_fixtures::CliResult cli =
      Run("design " + scenario +
          " --durations 20,10 --periods 30:12 --amplitudes 360:90 "
          "--static-duration 60 --static-positions 6 --target K=2 --design-duration 20 -o " +
          Path("out.json"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  DesignSettings s;
  s.durations_s = {20, 10};
  s.periods_s = {{30, 12}};
  s.amplitudes_deg = {{360, 90}};
  s.static_duration_s = 60;
  s.static_positions = 6;
  s.targets = ParseDesignTargets("K=2");
  s.design_duration_s = 20;
  const DesignOutcome o = DesignRun(s, scenario, LoadScenario(scenario), Session());
  EXPECT_EQ(o.options.durations_s, (std::vector<double>{10, 20}));
  EXPECT_EQ(Comparable(o.json), Out("out.json"));
}


// A scenario with a gyro block: its parameters in every table of the study,
// their sigma falling as 1/sqrt(duration) on the swing, not determined by the
// (accelerometer's) static method, and the same as `observability` gives for
// the scenario's own profile. A gyro target needs a gyro in the scenario.
TEST_F(DesignJob, CarriesTheGyroOfTheScenario) {
  const std::string profile =
      "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 40, rate_hz: 25}\n"
      "truth: {Kx: 171.5, W0x: 1504.2}\n"
      "noise: {accel_mV: 2, angle_arcsec: 15, gyro_dps: 0.05}\n";
  const std::string scenario = WriteText(
      "scenario.yaml", profile + "run:\n  gyro: {scale: [1, 1, 1], noise_dps: 0.05}\n");
  DesignSettings s;
  s.durations_s = {40, 160};
  s.periods_s = {{30, 12}};
  s.amplitudes_deg = {{360, 90}};
  s.static_duration_s = 60;
  s.targets = ParseDesignTargets("gyro.Kx=0.001");
  s.design_duration_s = 40;
  const DesignOutcome o = DesignRun(s, scenario, LoadScenario(scenario), Session());
  ASSERT_TRUE(o.layout.has_gyro());
  const nlohmann::json& qh = o.json["duration"]["quasi_harmonic"];
  for (const char* name : {"gyro.Kx", "gyro.W0y", "gyro.alpha_x", "gyro.Gzz"}) {
    SCOPED_TRACE(name);
    const double s40 = qh["sigma"][name][0], s160 = qh["sigma"][name][1];
    EXPECT_GT(s40, 0.0);
    EXPECT_NEAR(s160 / s40, 0.5, 0.05);  // four times the run, half the sigma
    EXPECT_EQ(o.json["comparison"]["rows"][name]["ratio_static_over_quasi_harmonic"],
              nullptr);
  }
  EXPECT_TRUE(o.json["targets"][0]["reached"].get<bool>()) << o.json["targets"].dump();
  const testing_fixtures::CliResult obs =
      Run("observability " + scenario + " -o " + Path("obs.json"));
  ASSERT_EQ(obs.exit_code, 0) << obs.err;
  const nlohmann::json crb = Out("obs.json");
  for (const char* name : {"gyro.Kx", "gyro.Ky", "gyro.W0z", "gyro.beta_z", "gyro.Gxy"}) {
    SCOPED_TRACE(name);
    const double design = qh["sigma"][name][0];
    const double observability = crb["crb"][name];
    EXPECT_NEAR(design / observability, 1.0, 1e-6);
  }

  std::string without = profile;
  without.replace(without.find(", gyro_dps: 0.05"), 16, "");
  const std::string plain = WriteText("plain.yaml", without);
  EXPECT_EQ(ErrorOf([&] { DesignRun(s, plain, LoadScenario(plain), Session()); }),
            "--target: unknown parameter or group 'gyro.Kx' (a parameter name or K, W0, "
            "angles, K_ij, bench, dR)");
}


}  // namespace
}  // namespace triadcal

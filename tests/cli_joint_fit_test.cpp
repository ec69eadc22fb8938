// `triadcal fit` on several runs (docs/multi-run.md) at the command line:
// runs simulated at three temperatures with a temperature model in a runs
// file, the joint OUT.json, `apply` with it, and bad input (runs of another
// IMU, a run listed twice, a per-run name that is not a parameter), each an
// exact one-line error with exit 2 and no output file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/file_util.h"
#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::RunTriadcal;

class JointFitCli : public testing_fixtures::TempDirTest {
 protected:
  // A 40-s paper run at 50 Hz at temperature T: W0x and Kx change with it.
  std::string Simulate(const std::string& name, double T, int seed) {
    const std::string scenario = WriteText(name + ".scenario.yaml", R"(
profile: {duration_s: 40, rate_hz: 50}
truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3,
        dpsi: -33, dtheta_c: 43, dlambda2: -33, dx2: -7, dy2: 16, dz2: 4}
noise: {accel_mV: 2.0, angle_arcsec: 15}
temperature: {start_C: )" + std::to_string(T) + R"(}
truth_temperature: {reference_C: 20, per_C: {W0x: 0.05, Kx: 0.02}}
run:
  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}
  constraints:
    - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
)");
    const auto r = RunTriadcal("simulate " + scenario + " -o " + Path(name) + " --seed " +
                                   std::to_string(seed),
                               Path("sim.err"));
    EXPECT_EQ(r.status, 0) << r.err;
    return Path(name + "/run.yaml");
  }

  void ExpectError(const std::string& args, const std::string& what, bool out_json = true) {
    const auto r = RunTriadcal(args, Path("stderr.txt"));
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err, "triadcal: error: " + what + "\n") << args;
    if (out_json) {
      EXPECT_FALSE(fs::exists(Path("out.json"))) << args;
    }
  }
};

TEST_F(JointFitCli, TemperatureModelFromThreeRunsAndApplyUsesIt) {
  Simulate("cold", 0.0, 1);
  Simulate("room", 20.0, 2);
  Simulate("hot", 40.0, 3);
  const std::string runs = WriteText("runs.yaml", R"(runs:
  - cold/run.yaml
  - {run: room/run.yaml, name: room}
  - {run: hot/run.yaml}
temperature: {reference_C: 20, degree: {W0x: 1, Kx: 1}}
)");
  const auto r = RunTriadcal("fit " + runs + " -o " + Path("out.json"), Path("fit.err"));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("out.json")));
  EXPECT_EQ(j["kind"], "joint");
  EXPECT_EQ(j["termination"].get<std::string>().rfind("converged in ", 0), 0u) << j["termination"];
  EXPECT_EQ(j["axes"], "imu");
  EXPECT_EQ(j["temperature_model"]["reference_C"], 20.0);
  ASSERT_EQ(j["runs"].size(), 3u);
  EXPECT_EQ(j["runs"][0]["name"], "cold");
  EXPECT_NEAR(j["runs"][0]["temperature_C"].get<double>(), 0.0, 1e-9);  // the temp_C column
  const struct {
    const char* name;
    const char* unit;
    double truth;
  } checks[] = {{"W0x.t1", "mV/degC", 0.05}, {"Kx.t1", "mV/g/degC", 0.02},
                {"W0x", "mV", 1504.2},      {"Kx", "mV/g", 171.5}};
  for (const auto& c : checks) {
    const nlohmann::json& p = j["parameters"][c.name];
    EXPECT_EQ(p["unit"], c.unit) << c.name;
    EXPECT_LT(std::abs(p["value"].get<double>() - c.truth) / p["sigma"].get<double>(), 4.0)
        << c.name << " " << p.dump();
  }
  EXPECT_FALSE(j["parameters"].contains("dpsi@room"));  // per run: under runs[]
  EXPECT_TRUE(j["runs"][1]["parameters"].contains("dpsi"));
  for (const auto& run : j["runs"]) EXPECT_TRUE(run["consistency"]["consistent"]) << run.dump();

  // apply evaluates the temperature model at each sample's temp_C.
  const auto a = RunTriadcal("apply " + Path("out.json") + " " + Path("hot/run.yaml") + " -o " +
                                 Path("hot.csv"),
                             Path("apply.err"));
  EXPECT_EQ(a.status, 0) << a.err;
  EXPECT_TRUE(fs::exists(Path("hot.csv")));
  // export holds one set of parameters: a temperature model is refused.
  ExpectError("export " + Path("out.json") + " --format yaml -o " + Path("cal.yaml"),
              Path("out.json") + ": temperature_model: a calibration with a temperature model "
                                 "cannot be exported (apply evaluates it; export a fit at one "
                                 "temperature)",
              false);
  EXPECT_FALSE(fs::exists(Path("cal.yaml")));
}

TEST_F(JointFitCli, ObservabilityOfTheRunsTogether) {
  const std::string a = Simulate("a", 20.0, 1);
  const std::string b = Simulate("b", 20.0, 2);
  const auto r = RunTriadcal("observability " + a + " " + b + " -o " + Path("obs.json"),
                             Path("obs.err"));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("obs.json")));
  EXPECT_EQ(j["kind"], "joint");
  EXPECT_GT(j["parameters"]["Kx"]["crb_sigma"].get<double>(), 0.0);
  EXPECT_NEAR(j["parameters"]["Kx"]["information_share"]["a"].get<double>(), 0.5, 0.05);
  EXPECT_TRUE(j["parameters"].contains("dpsi@b"));
  EXPECT_EQ(j["runs"].size(), 2u);
  ExpectError("observability " + a + " " + b + " --at " + a + " -o " + Path("out.json"),
              "--at: not available for several runs yet");
}

// Two single-axis runs of the same mounting: the shaft's scale factor Ky is
// held by each alone, and together they do not determine it either (the same
// axis never leaves the horizontal). The joint decision, at the nominal
// values as a single run's, holds it. Decided at the runs' own estimates (their
// misalignments away from 0) Ky drew information from its product with them:
// "Ky 1000 +- 100 mV/g", its prior sigma, "determined only by the runs
// together".
TEST_F(JointFitCli, TwoShaftsAlikeDoNotDetermineWhatNeitherDetermines) {
  const std::string scenario = WriteText("roll.yaml", R"(
profile: {amplitude_deg: [90, 0], period_s: [20, 12], duration_s: 120, rate_hz: 50}
truth: {Kx: 1004, Ky: 996, Kz: 1010, W0x: 25, W0y: -40, W0z: 60, alpha_x: 30, alpha_y: -20,
        beta_x: 25, beta_z: 15, gamma_y: -30, gamma_z: 20}
noise: {accel_mV: 3, angle_arcsec: 20}
run:
  triad: {scale_mV_per_g: [1000, 1000, 1000], bias_mV: [0, 0, 0], noise_mV: 3}
  constraints: []
)");
  std::string runs;
  for (const char* name : {"r1", "r2"}) {
    const auto s = RunTriadcal("simulate " + scenario + " -o " + Path(name) + " --seed " +
                                   std::string(name + 1),
                               Path("sim.err"));
    ASSERT_EQ(s.status, 0) << s.err;
    const std::string yaml = Path(std::string(name) + "/run.yaml");
    WriteText(std::string(name) + "/run.yaml",
              ReadFile(yaml) + "columns:\n  lambda2: {value: 0}\n");  // no inner axis
    runs += " " + yaml;
  }
  const auto f = RunTriadcal("fit" + runs + " -o " + Path("fit.json") + " -q", Path("fit.err"));
  ASSERT_EQ(f.status, 0) << f.err;
  const nlohmann::json fit = nlohmann::json::parse(ReadFile(Path("fit.json")));
  for (const nlohmann::json& run : fit["runs"]) {
    const nlohmann::json& held = run["alone"]["held"];
    EXPECT_NE(std::find(held.begin(), held.end(), "Ky"), held.end()) << run["name"];
  }
  EXPECT_TRUE(fit["parameters"]["Ky"].value("held", false)) << fit["parameters"]["Ky"].dump();
  const nlohmann::json& jointly = fit["determined_jointly_only"];
  EXPECT_EQ(std::find(jointly.begin(), jointly.end(), "Ky"), jointly.end()) << jointly.dump();
}

TEST_F(JointFitCli, BadInputIsOneLineNamingTheRun) {
  const std::string a = Simulate("a", 20.0, 1);
  const std::string b = Simulate("b", 20.0, 2);
  ExpectError("fit " + a + " " + a + " -o " + Path("out.json"),
              "command line: run 2 (" + a + "): " + a + " is listed twice (also command line: "
              "run 1 (" + a + "))");
  // Another IMU: another nominal scale factor.
  std::string text = ReadFile(b);
  const std::string from = "scale_mV_per_g: [174, 174, 174]";
  ASSERT_NE(text.find(from), std::string::npos) << text;
  text.replace(text.find(from), from.size(), "scale_mV_per_g: [174, 300, 174]");
  WriteText("b/other.yaml", text);
  ExpectError("fit " + a + " " + Path("b/other.yaml") + " -o " + Path("out.json"),
              "command line: run 'other' (" + Path("b/other.yaml") + ") declares another IMU: "
              "its triad in the IMU's own axes (mounting undone) has scale_mV_per_g [174, 300, "
              "174] and bias_mV [1500, 1500, 1500], run 'a' has [174, 174, 174] and [1500, "
              "1500, 1500] (runs of one IMU declare the same nominal triad)");
  const std::string runs = WriteText("runs.yaml", "runs: [a/run.yaml, b/run.yaml]\nper_run: [W0q]\n");
  ExpectError("fit " + runs + " -o " + Path("out.json"),
              runs + ": per_run: 'W0q' is not a parameter (see `triadcal params`)");
  // An effect's parameter without the effect (the roll-pitch example's runs
  // file lists thermal_drift's; its run.sh fits with --effects).
  const std::string drift =
      WriteText("drift.yaml", "runs: [a/run.yaml, b/run.yaml]\nper_run: [thermal_drift.rate_x]\n");
  ExpectError("observability " + drift + " -o " + Path("out.json"),
              drift + ": per_run: 'thermal_drift.rate_x' is a parameter of the effect "
                      "thermal_drift, which this command does not estimate (add --effects "
                      "thermal_drift)");
  ExpectError("fit " + drift + " --effects angle_latency -o " + Path("out.json"),
              drift + ": per_run: 'thermal_drift.rate_x' is a parameter of the effect "
                      "thermal_drift, which this command does not estimate (add --effects "
                      "thermal_drift)");
  const std::string twice = WriteText("twice.yaml", "runs: [a/run.yaml, {run: a/run.yaml, name: again}]\n");
  ExpectError("fit " + twice + " -o " + Path("out.json"),
              twice + ": runs[1]: " + Path("a/run.yaml") + " is listed twice (also " + twice +
                  ": runs[0])");
  // A --hold name that is no joint unknown (dpsi alone means dpsi@RUN of every run).
  ExpectError("fit " + a + " " + b + " --hold dpsy -o " + Path("out.json"),
              "--hold: unknown parameter 'dpsy' in this joint fit (a shared parameter such as "
              "Kx, a per-run one such as dpsi@RUN, or dpsi for every run)");
}

}  // namespace
}  // namespace triadcal

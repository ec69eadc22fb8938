// The gyro triad's input at the command line (SPEC section 10): each bad gyro
// input gives exit 2, exactly one line on stderr and no output file; gyro
// columns without a gyro block give one warning line and the fit of the
// accelerometer as before. The runs are the fixture's simulated paper run,
// here with a gyro.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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

// Several runs together calibrate the accelerometer triad only: runs that
// carry a gyro are named, once, in a warning and in the OUT of the joint fit
// and of the joint observability (before, the gyro was dropped silently).
TEST_F(CliGyroInput, SeveralRunsTogetherNameTheGyroTheyDoNotCalibrate) {
  for (const char* copy : {"b.csv", "c.csv"}) {
    std::filesystem::copy_file(Path("gyro.csv"), Path(copy));  // a run listed twice is refused
  }
  const std::string a = WriteText("a.yaml", "data: gyro.csv\ngyro: {}\n");
  const std::string b = WriteText("b.yaml", "data: b.csv\n");  // gyro columns, no block
  const std::string c = WriteText("c.yaml", "data: c.csv\ngyro: {}\n");
  const std::string warning =
      "triadcal: warning: runs a, c carry a gyro, which several runs together do not calibrate "
      "yet: the accelerometer triad only (fit each run alone for its gyro)\n";
  for (const char* command : {"observability", "fit"}) {
    const std::string out = Path(std::string(command) + ".json");
    const testing_fixtures::CliResult r =
        Run(std::string(command) + " " + a + " " + b + " " + c + " -o " + out + " -q");
    ASSERT_EQ(r.exit_code, 0) << command << ": " << r.err;
    const std::size_t at = r.err.find(warning);
    EXPECT_NE(at, std::string::npos) << command << ": " << r.err;
    EXPECT_EQ(r.err.find(warning, at + 1), std::string::npos) << command << ": said twice";
    const nlohmann::json j = nlohmann::json::parse(ReadFile(out));
    EXPECT_EQ(j["gyro_not_calibrated"]["runs"], nlohmann::json({"a", "c"})) << command;
    for (const auto& [name, p] : j["parameters"].items()) {
      EXPECT_NE(name.rfind("gyro.", 0), 0u) << command << ": " << name;
    }
  }
}

// The fit's OUT carries the gyro's own verdict, residual analysis and plot
// (the HTML report's gyro section); the accelerometer's keys as before. A
// gyro whose scale differs with the rate's sign (1 %, not in the model)
// fails the verdict: its increment residuals are not white.
TEST_F(CliGyroInput, FitOutCarriesTheGyrosVerdictResidualAndSpectrum) {
  const testing_fixtures::CliResult r = Run(Fit("data: gyro.csv\ngyro: {}\n"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json out = nlohmann::json::parse(ReadFile(Path("out.json")));
  EXPECT_EQ(out["residual_plot"]["unit"], "mg");
  EXPECT_EQ(out["residual_plot"]["spectrum"]["unit"], "mg^2 (periodogram |X_k|^2 / N)");
  EXPECT_EQ(out["residual_analysis"]["channels"].size(), 9u);
  const nlohmann::json& g = out["gyro"];
  const nlohmann::json& v = g["verdict"];
  EXPECT_EQ(v["pass"], true) << v.dump();
  EXPECT_EQ(v["residual_white"], true) << v.dump();
  EXPECT_EQ(v["sentence"].get<std::string>().rfind("gyro increment residuals white", 0), 0u)
      << v["sentence"];
  const nlohmann::json& plot = g["residual_plot"];
  EXPECT_EQ(plot["unit"], "arcsec");
  EXPECT_EQ(plot["spectrum"]["unit"], "arcsec^2 (periodogram |X_k|^2 / N)");
  ASSERT_EQ(plot["channels"].size(), 3u);
  EXPECT_EQ(plot["channels"][0]["name"], "gyro increment residual inner");
  EXPECT_EQ(plot["channels"][2]["values"].size(), plot["t_s"].size());
  EXPECT_GT(plot["t_s"].size(), 100u);  // 20 s in intervals of 0.1 s
  EXPECT_GT(plot["spectrum"]["freq_hz"].size(), 50u);
  // The channels' RMS are those OUT gave before, per component.
  EXPECT_NEAR(plot["channels"][1]["rms"].get<double>(),
              g["residual_rms_arcsec"]["outer"].get<double>(), 1e-9);
  const nlohmann::json& ra = g["residual_analysis"];
  ASSERT_EQ(ra["channels"].size(), 6u);
  EXPECT_EQ(ra["channels"][3]["channel"], "whitened gyro increment inner");
  EXPECT_EQ(ra["channels"][3]["in_whiteness_test"], true);
  EXPECT_NEAR(ra["channels"][3]["rms"].get<double>(), 1.0, 0.15);

  RunData d = gyro_run_;
  for (auto& ch : d.gyro_rad_s) {
    for (double& w : ch) w += 0.01 * std::abs(w);
  }
  WriteRunCsv(d, Path("gyro.csv"), "");
  const testing_fixtures::CliResult a = Run(Fit("data: gyro.csv\ngyro: {}\n"));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const nlohmann::json asym = nlohmann::json::parse(ReadFile(Path("out.json")));
  const nlohmann::json& va = asym["gyro"]["verdict"];
  EXPECT_EQ(va["pass"], false) << va.dump();
  EXPECT_EQ(va["residual_white"], false) << va.dump();
  EXPECT_NE(va["sentence"].get<std::string>().find("NOT WHITE"), std::string::npos)
      << va["sentence"];
}

// A scenario with a gyro block: montecarlo and observability carry the
// gyro's parameters. The batch fit and the filter (EKF and RTS, with the
// gyro's increments as measurements, as `filter` runs) estimate them against
// their Cramer-Rao bound: every run's RTS (the filter's result) and batch
// estimate of each gyro parameter within 4 sigma of the truth. The EKF's (the
// first forward pass's) gyro estimates are recorded too; they are not as
// honest (docs/method.md section 11), and printed. The summary names them
// with their units; before, both left the gyro out and then the filter did.
TEST_F(CliGyroInput, MonteCarloAndObservabilityCarryTheGyro) {
  const std::string sc = WriteText(
      "sc.yaml",
      "seed: 3\n"
      "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 30, rate_hz: 50}\n"
      "truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3, "
      "gyro.Kx: 1.004, gyro.W0y: -0.5}\n"
      "noise: {accel_mV: 0.97, angle_arcsec: 15, gyro_dps: 0.05}\n"
      "run:\n"
      "  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}\n"
      "  gyro: {noise_dps: 0.05}\n"
      "  constraints: [{expr: \"dpsi - dlambda2\", value_arcmin: 0, sigma_arcsec: 30}]\n");
  // The summary on stdout.
  const int status =
      std::system((std::string(TRIADCAL_BIN) + " montecarlo " + sc + " -n 4 --per-seed -o " +
                   Path("mc.json") + " > " + Path("summary.txt") + " 2> " + Path("err.txt"))
                      .c_str());
  ASSERT_EQ(status, 0) << ReadFile(Path("err.txt"));
  const nlohmann::json m = nlohmann::json::parse(ReadFile(Path("mc.json")));
  for (const char* name : {"gyro.Kx", "gyro.W0y", "gyro.alpha_x", "gyro.Gzz"}) {
    const nlohmann::json& p = m["parameters"][name];
    ASSERT_TRUE(p.is_object()) << name;
    EXPECT_GT(p["crb"].get<double>(), 0.0) << name;
    for (const char* est : {"ekf", "rts", "batch"}) {
      EXPECT_EQ(p[est]["held_runs"], 0) << name << " " << est;
      EXPECT_FALSE(p[est].contains("estimated")) << name << " " << est;
      EXPECT_GT(p[est]["mean_sigma"].get<double>(), 0.0) << name << " " << est;
    }
    EXPECT_LT(p["batch"]["max_abs_normalised_error"].get<double>(), 4.0) << name;
  }
  // Every run's record: each gyro parameter of the smoother within 4 sigma.
  const nlohmann::json& names = m["per_seed"]["parameters"];
  ASSERT_EQ(m["per_seed"]["runs"].size(), 4u);
  double ss_rts = 0.0, ss_ekf = 0.0, worst_rts = 0.0;
  int count = 0;
  for (const nlohmann::json& run : m["per_seed"]["runs"]) {
    ASSERT_TRUE(run["rts"].is_object()) << run.dump();
    for (std::size_t i = 0; i < names.size(); ++i) {
      const std::string name = names[i].get<std::string>();
      if (name.rfind("gyro.", 0) != 0) continue;
      const double z = run["rts"]["error"][i].get<double>() / run["rts"]["sigma"][i].get<double>();
      const double z_ekf =
          run["ekf"]["error"][i].get<double>() / run["ekf"]["sigma"][i].get<double>();
      EXPECT_LT(std::abs(z), 4.0) << name << " seed " << run["seed"];
      worst_rts = std::max(worst_rts, std::abs(z));
      ss_rts += z * z;
      ss_ekf += z_ekf * z_ekf;
      ++count;
    }
  }
  EXPECT_EQ(count, 4 * 21);
  std::printf("gyro parameters over 4 seeds: RTS RMS z %.2f (largest |z| %.2f), EKF RMS z %.2f\n",
              std::sqrt(ss_rts / count), worst_rts, std::sqrt(ss_ekf / count));
  // The summary's table names the gyro's parameters with their units, in
  // columns as wide as they are.
  const std::string summary = ReadFile(Path("summary.txt"));
  for (const char* row : {"\ngyro.alpha_x arcmin    ", "\ngyro.Gzz     (deg/s)/g ",
                          "\ngyro.W0y     deg/s     ", "\ngyro.Kx      1         "}) {
    EXPECT_NE(summary.find(row), std::string::npos) << row << "\n" << summary;
  }
  EXPECT_EQ(summary.find("not estimated by"), std::string::npos) << summary;
  // Sharded and merged, the same (the merge makes the layout with the gyro).
  for (const char* i : {"1", "2"}) {
    const testing_fixtures::CliResult sh = Run("montecarlo " + sc + " -n 4 --shard " + i +
                                               "/2 -o " + Path(std::string("mc") + i + ".json"));
    ASSERT_EQ(sh.exit_code, 0) << sh.err;
  }
  const testing_fixtures::CliResult mg = Run("merge " + Path("mc1.json") + " " +
                                             Path("mc2.json") + " -o " + Path("merged.json"));
  ASSERT_EQ(mg.exit_code, 0) << mg.err;
  const nlohmann::json merged = nlohmann::json::parse(ReadFile(Path("merged.json")));
  EXPECT_EQ(merged["parameters"]["gyro.Kx"]["batch"], m["parameters"]["gyro.Kx"]["batch"]);
  EXPECT_EQ(merged["parameters"]["gyro.Kx"]["rts"], m["parameters"]["gyro.Kx"]["rts"]);
  const testing_fixtures::CliResult ob = Run("observability " + sc + " -o " + Path("obs.json"));
  ASSERT_EQ(ob.exit_code, 0) << ob.err;
  const nlohmann::json o = nlohmann::json::parse(ReadFile(Path("obs.json")));
  EXPECT_NEAR(o["crb"]["gyro.Kx"].get<double>(), m["parameters"]["gyro.Kx"]["crb"].get<double>(),
              1e-12);
  EXPECT_LT(o["crb"]["gyro.Kx"].get<double>(), 1e-3);  // prior 0.1: determined
}

// A 60-s paper-like scenario at 50 Hz with a gyro (seed 5, 0.05 deg/s of
// gyro noise, declared so): the triad's truth, `gyro_truth` added to it,
// and `effects` (an effects: block, or empty).
std::string GyroScenario(const std::string& gyro_truth, const std::string& effects) {
  return "seed: 5\n"
         "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 60, rate_hz: 50}\n"
         "truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1504.2, W0z: 1504.3, " +
         gyro_truth + "}\n" +
         "noise: {accel_mV: 0.97, angle_arcsec: 15, gyro_dps: 0.05}\n" + effects +
         "run:\n"
         "  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500]}\n"
         "  gyro: {noise_dps: 0.05}\n"
         "  constraints: [{expr: \"dpsi - dlambda2\", value_arcmin: 0, sigma_arcsec: 30}]\n";
}

// The point the decision linearises at (the nominal values with the scale
// factors and zero offsets fitted; `--init nominal` starts there) fits the
// gyro's zero offsets, not its scale factors: its rate residuals' weights
// follow them, and with its noise held nothing balances that. A large
// g-sensitivity left in the residual (the real fast roll run's is -23
// (deg/s)/g) ran gyro.Ky off to 0.775 (truth 1) with them free.
TEST_F(CliGyroInput, TheDecisionsPointDoesNotRunOffAlongTheGyroScaleFactors) {
  const std::string sc = WriteText(
      "gsens.yaml",
      GyroScenario("gyro.Kx: 1.004, gyro.W0x: 2.0, gyro.W0y: -0.5, gyro.W0z: 1.0, gyro.Gyx: -20",
                   ""));
  ASSERT_EQ(Run("simulate " + sc + " -o " + Path("gsens") + " -q").exit_code, 0);
  const testing_fixtures::CliResult r =
      Run("fit " + Path("gsens/run.yaml") + " --init nominal -o " + Path("g.json") + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json start = nlohmann::json::parse(ReadFile(Path("g.json")))["initial"];
  for (const char* k : {"gyro.Kx", "gyro.Ky", "gyro.Kz"}) {
    EXPECT_NEAR(start["parameters"][k]["value"].get<double>(), 1.0, 0.01) << k;
  }
  // Its zero offsets are fitted (gyro.W0y also takes what the g-sensitivity
  // leaves along the shaft's gravity).
  EXPECT_NEAR(start["parameters"]["gyro.W0x"]["value"].get<double>(), 2.0, 0.05);
  EXPECT_NEAR(start["parameters"]["gyro.W0z"]["value"].get<double>(), 1.0, 0.05);
}

// diagnose on a run with a gyro (SPEC section 10): every fit of the loop
// estimates the gyro beside the accelerometer, each state of OUT carries the
// gyro's noise, verdict and residual, and an undeclared angle latency -- one
// time offset shared by both triads -- is found. Left out, the latency fails
// the gyro's verdict (and moves gyro.Gzy by 4.8 sigma on this seed); after
// the loop the verdict passes and every gyro parameter the run determines is
// within 4 sigma of the truth.
TEST_F(CliGyroInput, DiagnoseCarriesTheGyroAndFindsTheSharedLatency) {
  const std::string sc =
      WriteText("sc.yaml", GyroScenario("gyro.Kx: 1.004, gyro.W0y: -0.5, gyro.Gxz: 0.05",
                                        "effects:\n  angle_latency: {tau_ms: 5.0}\n"));
  ASSERT_EQ(Run("simulate " + sc + " -o " + Path("sim") + " -q").exit_code, 0);
  const testing_fixtures::CliResult r =
      Run("diagnose " + Path("sim/run.yaml") + " -o " + Path("d.json") +
          " --candidates angle_latency,thermal_drift");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json d = nlohmann::json::parse(ReadFile(Path("d.json")));
  EXPECT_EQ(d["selected"], nlohmann::json::array({"angle_latency"})) << d["selected"];
  for (const char* state : {"before", "after"}) {
    const nlohmann::json& g = d[state]["gyro"];
    ASSERT_TRUE(g.is_object()) << state;
    EXPECT_GT(g["noise"]["estimated_dps"][0].get<double>(), 0.0) << state;
    EXPECT_TRUE(g["verdict"].contains("pass")) << state;
    EXPECT_EQ(g["residual_plot"]["unit"], "arcsec") << state;
  }
  // Left out, the latency shows in the gyro's residual; found, it is gone.
  EXPECT_EQ(d["before"]["gyro"]["verdict"]["pass"], false) << d["before"]["gyro"]["verdict"];
  EXPECT_EQ(d["after"]["gyro"]["verdict"]["pass"], true) << d["after"]["gyro"]["verdict"];
  const nlohmann::json truth =
      nlohmann::json::parse(ReadFile(Path("sim/truth.json")))["parameters"];
  int judged = 0;
  for (const auto& [name, p] : d["after"]["parameters"].items()) {
    if (name.rfind("gyro.", 0) != 0 || !p.contains("sigma") || !p["sigma"].is_number()) continue;
    if (!p.value("estimable", false)) continue;  // held or not determined
    ASSERT_TRUE(truth.contains(name)) << name;
    const double t = truth[name].get<double>();
    EXPECT_LT(std::abs(p["value"].get<double>() - t), 4.0 * p["sigma"].get<double>()) << name;
    ++judged;
  }
  EXPECT_GE(judged, 15);
}

// filter and compare on a run with a gyro estimate it beside the
// accelerometer (the filter takes the gyro's increments as measurements,
// docs/method.md section 11): no warning, the gyro's parameters with a sigma,
// and OUT's "gyro" with every key of fit's (compare: the smoother's and the
// batch's); before, both left the gyro out with a warning.
TEST_F(CliGyroInput, FilterAndCompareCarryTheGyro) {
  const std::string yaml = WriteText("g.yaml", "data: gyro.csv\ngyro: {}\n");
  const testing_fixtures::CliResult fit = Run("fit " + yaml + " -o " + Path("fit.json"));
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const nlohmann::json fit_gyro = nlohmann::json::parse(ReadFile(Path("fit.json")))["gyro"];
  auto has_fit_keys = [&](const nlohmann::json& g, const std::string& what) {
    ASSERT_TRUE(g.is_object()) << what;
    for (const auto& [key, value] : fit_gyro.items()) {
      EXPECT_TRUE(g.contains(key)) << what << ": " << key;
    }
    for (const auto& [key, value] : fit_gyro["noise"].items()) {
      EXPECT_TRUE(g["noise"].contains(key)) << what << ": noise." << key;
    }
    EXPECT_EQ(g["noise"]["source"], "declared") << what;
    EXPECT_TRUE(g["verdict"].contains("pass")) << what;
  };
  const testing_fixtures::CliResult f = Run("filter " + yaml + " -o " + Path("f.json"));
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_EQ(f.err.find("gyro"), std::string::npos) << f.err;
  const nlohmann::json fo = nlohmann::json::parse(ReadFile(Path("f.json")));
  for (const char* section : {"ekf", "rts"}) {
    const nlohmann::json& p = fo[section]["parameters"]["gyro.Kx"];
    ASSERT_TRUE(p["sigma"].is_number()) << section << ": " << p.dump();
    EXPECT_LT(std::abs(p["value"].get<double>() - 1.0), 4.0 * p["sigma"].get<double>());
  }
  has_fit_keys(fo["gyro"], "filter");
  EXPECT_NEAR(fo["gyro"]["mean_nis"].get<double>(), 3.0, 0.5);
  EXPECT_NEAR(fo["gyro"]["noise"]["used_dps"][0].get<double>(), 0.05, 1e-3);

  const testing_fixtures::CliResult c = Run("compare " + yaml + " -o " + Path("c.json"));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(c.err.find("gyro"), std::string::npos) << c.err;
  const nlohmann::json co = nlohmann::json::parse(ReadFile(Path("c.json")));
  has_fit_keys(co["gyro"]["rts"], "compare rts");
  ASSERT_TRUE(co["gyro"]["batch"].is_object());
  EXPECT_EQ(co["gyro"]["batch"]["noise"]["source"], "estimated");
  const nlohmann::json& d = co["differences_in_sigma"]["gyro.W0y"];
  ASSERT_TRUE(d["batch_minus_rts"].is_number()) << d.dump();
  EXPECT_LT(std::abs(d["batch_minus_rts"].get<double>()), 0.5);

  // Without a gyro, nothing is said.
  const testing_fixtures::CliResult plain = Run("filter " + Path("run.yaml") + " -o " +
                                                Path("plain.json"));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.err.find("gyro"), std::string::npos) << plain.err;
  EXPECT_FALSE(nlohmann::json::parse(ReadFile(Path("plain.json"))).contains("gyro"));
}

}  // namespace
}  // namespace triadcal

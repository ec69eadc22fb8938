// `triadcal export`: the exported C99 code, compiled with `cc -std=c99 -Wall
// -Wextra -pedantic -Werror`, gives what `triadcal apply` gives to 1e-9 g on a
// simulated run with every K_ij non-zero (with and without the sensor-stage
// effects) and on the Ferraris real run, and with the gyro (and its effects)
// to 1e-9 deg/s; the
// matrix form reproduces the readings model (the gyro's too); bad options give
// their exact message.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/calibration_io.h"
#include "core/io/file_util.h"
#include "core/io/run_description_io.h"
#include "core/io/run_io.h"
#include "core/model/bench_model.h"
#include "core/model/effects.h"
#include "core/model/gyro_model.h"
#include "core/model/units.h"
#include "app/calibration_export.h"
#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::RunCommand;
using testing_fixtures::RunTriadcal;

// A short run on the paper's profile with every K_ij non-zero; `extra` adds
// scenario sections (effects, temperature).
std::string Scenario(const std::string& extra) {
  return "seed: 7\n"
         "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 30, rate_hz: 200}\n"
         "truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1498.0, W0z: 1502.5,\n"
         "        alpha_x: 16, alpha_y: -32, beta_x: 11, beta_z: 26, gamma_y: 140, gamma_z: 64,\n"
         "        Kxx: 0.002, Kxy: -0.0012, Kxz: 0.0007, Kyx: 0.0009, Kyy: -0.0015,\n"
         "        Kyz: -0.001, Kzx: 0.0011, Kzy: 0.0015, Kzz: -0.0008}\n"
         "noise: {accel_mV: 1, angle_arcsec: 15}\n" +
         extra;
}

class ExportTest : public testing_fixtures::TempDirTest {
 protected:
  std::string Err() const { return Path("err.txt"); }

  // W [g] per sample from `triadcal apply CAL RUN`, and with the gyro the
  // rates omega [deg/s] into *omega.
  std::vector<Eigen::Vector3d> Apply(const std::string& cal, const std::string& run_yaml,
                                     std::vector<Eigen::Vector3d>* omega = nullptr) {
    const auto r =
        RunTriadcal("apply " + cal + " " + run_yaml + " -o " + Path("applied.csv"), Err());
    EXPECT_EQ(r.status, 0) << r.err;
    std::vector<Eigen::Vector3d> W;
    std::ifstream in(Path("applied.csv"));
    std::string line;
    bool header = true;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      if (header) {
        header = false;
        // t,Wx,Wy,Wz[,omega_x,omega_y,omega_z],...
        EXPECT_EQ(line.rfind(omega ? "t,Wx,Wy,Wz,omega_x,omega_y,omega_z" : "t,Wx,Wy,Wz", 0), 0u)
            << line;
        continue;
      }
      std::stringstream ss(line);
      std::string cell;
      std::getline(ss, cell, ',');  // t
      Eigen::Vector3d w;
      for (int i = 0; i < 3; ++i) {
        std::getline(ss, cell, ',');
        w[i] = std::stod(cell);
      }
      W.push_back(w);
      if (!omega) continue;
      for (int i = 0; i < 3; ++i) {
        std::getline(ss, cell, ',');
        w[i] = std::stod(cell);
      }
      omega->push_back(w);
    }
    return W;
  }

  // Exports CAL as C, compiles it with a driver and runs it on every sample of
  // RUN: W [g] by NAME_apply, and with `omega` the rates [deg/s] by
  // NAME_apply_gyro from the run's gyro readings and that W.
  std::vector<Eigen::Vector3d> ExportedC(const std::string& cal, const std::string& run_yaml,
                                         std::vector<Eigen::Vector3d>* omega = nullptr) {
    const auto e = RunTriadcal("export " + cal + " --format c -o " + Path("cal.c"), Err());
    EXPECT_EQ(e.status, 0) << e.err;
    // The exported code alone, with every warning an error.
    const auto cc = RunCommand(
        "cc -std=c99 -Wall -Wextra -pedantic -Werror -c " + Path("cal.c") + " -o " + Path("cal.o"),
        Err());
    EXPECT_EQ(cc.status, 0) << cc.err;
    WriteText("driver.c",
              omega ? "#include <stdio.h>\n#include \"cal.h\"\n"
                      "int main(void) {\n"
                      "  double t, z[3], T, Tref, W[3], g[3], w[3];\n"
                      "  while (scanf(\"%lf %lf %lf %lf %lf %lf %lf %lf %lf\", &t, &z[0], &z[1], "
                      "&z[2], &T, &Tref, &g[0], &g[1], &g[2]) == 9) {\n"
                      "    cal_apply(z, t, T, Tref, W);\n"
                      "    cal_apply_gyro(g, W, w);\n"
                      "    printf(\"%.17g %.17g %.17g %.17g %.17g %.17g\\n\", W[0], W[1], W[2], "
                      "w[0], w[1], w[2]);\n"
                      "  }\n  return 0;\n}\n"
                    : "#include <stdio.h>\n#include \"cal.h\"\n"
                      "int main(void) {\n"
                      "  double t, z[3], T, Tref, W[3];\n"
                      "  while (scanf(\"%lf %lf %lf %lf %lf %lf\", &t, &z[0], &z[1], &z[2], &T, "
                      "&Tref) == 6) {\n"
                      "    cal_apply(z, t, T, Tref, W);\n"
                      "    printf(\"%.17g %.17g %.17g\\n\", W[0], W[1], W[2]);\n"
                      "  }\n  return 0;\n}\n");
    const auto link = RunCommand("cc -std=c99 -Wall -Werror " + Path("driver.c") + " " +
                                     Path("cal.o") + " -o " + Path("driver"),
                                 Err());
    EXPECT_EQ(link.status, 0) << link.err;

    const RunDescription run = LoadRunDescription(run_yaml);
    const RunData data = LoadRunData(run, nullptr);
    {
      std::ofstream in(Path("readings.txt"));
      char buf[512];
      for (std::size_t k = 0; k < data.size(); ++k) {
        const Eigen::Vector3d z = data.readings_mV(k);
        std::snprintf(buf, sizeof(buf), "%.17g %.17g %.17g %.17g %.17g %.17g", data.t_s[k], z[0],
                      z[1], z[2], data.has_temp() ? data.temp_C[k] : 0.0,
                      data.has_temp() ? data.temp_C.front() : 0.0);
        in << buf;
        if (omega) {
          // The gyro readings in deg/s, in the triad's axes (after run.yaml's
          // unit conversion and mounting).
          const Eigen::Vector3d g = data.gyro(k) / kDegToRad;
          std::snprintf(buf, sizeof(buf), " %.17g %.17g %.17g", g[0], g[1], g[2]);
          in << buf;
        }
        in << "\n";
      }
    }
    const auto r = RunCommand(
        Path("driver") + " < " + Path("readings.txt") + " > " + Path("c_out.txt") + " ; true",
        Err());
    std::vector<Eigen::Vector3d> W;
    std::ifstream out(Path("c_out.txt"));
    Eigen::Vector3d w, g;
    while (out >> w[0] >> w[1] >> w[2]) {
      W.push_back(w);
      if (omega && out >> g[0] >> g[1] >> g[2]) omega->push_back(g);
    }
    EXPECT_EQ(W.size(), data.size()) << r.err;
    if (omega) {
      EXPECT_EQ(omega->size(), data.size()) << r.err;
    }
    return W;
  }

  // Largest |C - apply| over every sample and axis [g]; with `gyro_dps`, the
  // same for the gyro's rates [deg/s] into *gyro_dps.
  double LargestDifference(const std::string& cal, const std::string& run_yaml,
                           double* gyro_dps = nullptr) {
    std::vector<Eigen::Vector3d> a_omega, c_omega;
    const std::vector<Eigen::Vector3d> a = Apply(cal, run_yaml, gyro_dps ? &a_omega : nullptr);
    const std::vector<Eigen::Vector3d> c = ExportedC(cal, run_yaml, gyro_dps ? &c_omega : nullptr);
    EXPECT_EQ(a.size(), c.size());
    EXPECT_GT(a.size(), 0u);
    double worst = 0.0;
    for (std::size_t k = 0; k < std::min(a.size(), c.size()); ++k) {
      worst = std::max(worst, (a[k] - c[k]).cwiseAbs().maxCoeff());
    }
    if (gyro_dps) {
      EXPECT_EQ(a_omega.size(), a.size());
      EXPECT_EQ(c_omega.size(), a.size());
      *gyro_dps = a_omega.empty() ? 1e300 : 0.0;
      for (std::size_t k = 0; k < std::min(a_omega.size(), c_omega.size()); ++k) {
        *gyro_dps = std::max(*gyro_dps, (a_omega[k] - c_omega[k]).cwiseAbs().maxCoeff());
      }
    }
    return worst;
  }

  std::string Simulate(const std::string& scenario_text) {
    const std::string scen = WriteText("scenario.yaml", scenario_text);
    const auto r = RunTriadcal("simulate " + scen + " -o " + Path("sim"), Err());
    EXPECT_EQ(r.status, 0) << r.err;
    return Path("sim/run.yaml");
  }
};

TEST_F(ExportTest, CMatchesApplyOnASimulatedRunWithEveryKij) {
  const std::string run = Simulate(Scenario(""));
  const double worst = LargestDifference(Path("sim/truth.json"), run);
  EXPECT_LE(worst, 1e-9);
  // The nonlinearity matters at this size: a wrong inverse would show.
  EXPECT_EQ(LoadCalibration(Path("sim/truth.json")).theta[kKxy], -0.0012);
}

// The gyro (SPEC section 10), every parameter of it non-zero and a reversed z
// gyro, on a run with the gyro's noise: NAME_apply_gyro gives the rates apply
// gives to 1e-9 deg/s, from the truth and from a fit.
const char kGyroScenario[] =
    "truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1498.0, W0z: 1502.5,\n"
    "        alpha_x: 16, alpha_y: -32, beta_x: 11, beta_z: 26, gamma_y: 140, gamma_z: 64,\n"
    "        Kxx: 0.002, Kxy: -0.0012, Kxz: 0.0007, Kyx: 0.0009, Kyy: -0.0015,\n"
    "        Kyz: -0.001, Kzx: 0.0011, Kzy: 0.0015, Kzz: -0.0008,\n"
    "        gyro.Kx: 1.004, gyro.Ky: 0.997, gyro.Kz: -1.002,\n"
    "        gyro.W0x: 0.31, gyro.W0y: -0.52, gyro.W0z: 0.2,\n"
    "        gyro.alpha_x: 12, gyro.alpha_y: -8, gyro.beta_x: 5, gyro.beta_z: 15,\n"
    "        gyro.gamma_y: -20, gyro.gamma_z: 7,\n"
    "        gyro.Gxx: 0.02, gyro.Gxy: 0.05, gyro.Gxz: -0.03, gyro.Gyx: 0.01, gyro.Gyy: -0.04,\n"
    "        gyro.Gyz: 0.02, gyro.Gzx: -0.01, gyro.Gzy: 0.03, gyro.Gzz: 0.06}\n"
    "noise: {accel_mV: 1, angle_arcsec: 15, gyro_dps: 0.05}\n"
    "run:\n"
    "  bench: {lever_arm_mm: [138, 20, 20], angle_noise_arcsec: 15}\n"
    "  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500], noise_mV: 1}\n"
    "  gyro: {scale: [1, 1, -1], noise_dps: 0.05}\n";

TEST_F(ExportTest, CGyroMatchesApply) {
  const std::string run = Simulate(
      "seed: 7\n"
      "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 30, rate_hz: 200}\n" +
      std::string(kGyroScenario));
  ASSERT_TRUE(LoadCalibration(Path("sim/truth.json")).layout.has_gyro());
  double gyro_dps = 0.0;
  EXPECT_LE(LargestDifference(Path("sim/truth.json"), run, &gyro_dps), 1e-9);
  EXPECT_LE(gyro_dps, 1e-9);
  // A fit of the run: its OUT carries the gyro too. (The outputs of the truth's
  // inputs go first: apply and export do not replace them.)
  for (const char* file : {"applied.csv", "cal.c", "cal.h"}) fs::remove(Path(file));
  const auto f = RunTriadcal("fit " + run + " -o " + Path("fit.json"), Err());
  ASSERT_EQ(f.status, 0) << f.err;
  ASSERT_TRUE(LoadCalibration(Path("fit.json")).layout.has_gyro());
  EXPECT_LE(LargestDifference(Path("fit.json"), run, &gyro_dps), 1e-9);
  EXPECT_LE(gyro_dps, 1e-9);
  EXPECT_NE(ReadFile(Path("cal.h"))
                .find("void cal_apply_gyro(const double g_dps[3], const double W_g[3], double "
                      "omega_dps[3]);"),
            std::string::npos);
}

// Without the gyro the C has no gyro function and the matrix form no "gyro".
TEST_F(ExportTest, NoGyroFunctionWithoutTheGyro) {
  Simulate(Scenario(""));
  const std::string cal = Path("sim/truth.json");
  ASSERT_EQ(RunTriadcal("export " + cal + " --format c -o " + Path("cal.c"), Err()).status, 0);
  EXPECT_EQ(ReadFile(Path("cal.h")).find("gyro"), std::string::npos);
  EXPECT_EQ(ReadFile(Path("cal.c")).find("gyro"), std::string::npos);
  ASSERT_EQ(
      RunTriadcal("export " + cal + " --format json-matrix -o " + Path("m.json"), Err()).status, 0);
  EXPECT_FALSE(nlohmann::json::parse(ReadFile(Path("m.json"))).contains("gyro"));
}

// The gyro's matrices (json-matrix and yaml): g = S omega + b + G W is the
// gyro's readings model in deg/s, and S_inverse its inverse.
TEST_F(ExportTest, GyroMatrixFormIsTheGyroReadingsModel) {
  Simulate(
      "seed: 7\n"
      "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 5, rate_hz: 50}\n" +
      std::string(kGyroScenario));
  const std::string truth = Path("sim/truth.json");
  for (const std::string format : {"json-matrix", "yaml"}) {
    const auto r = RunTriadcal(
        "export " + truth + " --format " + format + " -o " + Path("matrix." + format), Err());
    ASSERT_EQ(r.status, 0) << r.err;
  }
  const std::string yaml = ReadFile(Path("matrix.yaml"));
  for (const char* key : {"gyro:", "S_inverse:", "b_dps:", "G_dps_per_g:"}) {
    EXPECT_NE(yaml.find(key), std::string::npos) << key;
  }
  const nlohmann::json m = nlohmann::json::parse(ReadFile(Path("matrix.json-matrix")));
  ASSERT_TRUE(m.contains("gyro"));
  const nlohmann::json& gm = m["gyro"];
  const Calibration cal = LoadCalibration(truth);
  const ModelConfig cfg = MakeModelConfig(RunDescription(), cal.layout);
  auto matrix = [&](const char* key) {
    Eigen::Matrix3d a;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a(r, c) = gm[key][r][c].get<double>();
    }
    return a;
  };
  const Eigen::Matrix3d S = matrix("S"), S_inverse = matrix("S_inverse"), G = matrix("G_dps_per_g");
  const Eigen::Vector3d b(gm["b_dps"][0].get<double>(), gm["b_dps"][1].get<double>(),
                          gm["b_dps"][2].get<double>());
  EXPECT_LT((S * S_inverse - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(b[2], 0.2, 1e-15);
  EXPECT_NEAR(G(2, 2), 0.06, 1e-15);
  for (const Eigen::Vector3d& w_dps :
       {Eigen::Vector3d(30, -80, 5.2), Eigen::Vector3d(-100, 10, 200)}) {
    const Eigen::Vector3d W(0.3, -0.8, 0.52);
    const Eigen::Vector3d g_dps =
        GyroReadings(cfg, cal.theta.data(), Eigen::Vector3d(w_dps * kDegToRad), W) / kDegToRad;
    EXPECT_LT((S * w_dps + b + G * W - g_dps).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((S_inverse * (g_dps - b - G * W) - w_dps).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST_F(ExportTest, CMatchesApplyWithTheSensorStageEffects) {
  const std::string run =
      Simulate(Scenario("effects: {thermal_drift: {rate_x_mV_per_min: 0.5, rate_z: -0.25},\n"
                        "          thermal_drift_temp: {coef_y_mV_per_degC: 0.3, coef_z: -0.2},\n"
                        "          scale_asymmetry: {dKx: 0.4, dKy: -0.3, dKz: 0.2},\n"
                        "          cross_quadratic: {x_yy_zz: 0.004, x_yz: -0.003, y_xx_zz: 0.005,\n"
                        "                            y_xz: 0.002, z_xx_yy: -0.004, z_xy: 0.003}}\n"
                        "temperature: {start_C: 20, rate_C_per_h: 10}\n"));
  const Calibration cal = LoadCalibration(Path("sim/truth.json"));
  ASSERT_TRUE(cal.layout.has(Effect::kThermalDrift));
  ASSERT_TRUE(cal.layout.has(Effect::kThermalDriftTemp));
  ASSERT_TRUE(cal.layout.has(Effect::kScaleAsymmetry));
  ASSERT_TRUE(cal.layout.has(Effect::kCrossQuadratic));
  EXPECT_EQ(cal.theta[cal.layout.offset(Effect::kCrossQuadratic) + 2], 0.005);
  EXPECT_LE(LargestDifference(Path("sim/truth.json"), run), 1e-9);
}

// Every sensor- and gyro-stage effect of the catalogue, alone at its typical
// size (a gyro-stage one on the gyro run of kGyroScenario, whose z gyro is
// reversed): each exported form carries it (the C gives what apply gives, to
// 1e-9 g and 1e-9 deg/s, from the truth and for a gyro-stage effect from a fit
// with --effects; the matrix forms name it) or export refuses it by name
// (exit 2, no file). None is silently left out.
TEST_F(ExportTest, EverySensorAndGyroStageEffectIsCarriedOrRefusedByName) {
  int carried = 0, refused = 0, gyro_carried = 0;
  for (const EffectSpec& e : EffectCatalogue()) {
    if (e.stage != EffectStage::kSensor && e.stage != EffectStage::kGyro) continue;
    const bool gyro = e.stage == EffectStage::kGyro;
    SCOPED_TRACE(e.name);
    std::string params;
    for (const ParamSpec& p : e.params) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%.6g", TypicalValue(e, p, 175.8));
      params += (params.empty() ? "" : ", ") + p.name + ": " + buf;
    }
    fs::remove_all(Path("sim"));
    const std::string effects = "effects: {" + e.name + ": {" + params + "}}\n";
    const std::string run =
        gyro ? Simulate("seed: 7\n"
                        "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 30, "
                        "rate_hz: 200}\n" +
                        std::string(kGyroScenario) + effects)
             : Simulate(Scenario(effects + (e.needs.temp_C
                                                ? "temperature: {start_C: 20, rate_C_per_h: 10}\n"
                                                : "")));
    const std::string truth = Path("sim/truth.json");
    ASSERT_TRUE(LoadCalibration(truth).layout.has(e.id));
    const std::string refusal = ExportRefusal(LoadCalibration(truth));
    for (const std::string format : {"c", "yaml", "json-matrix"}) {
      const std::string out = Path(e.name + (format == "c" ? ".c" : "." + format));
      const auto r = RunTriadcal("export " + truth + " --format " + format + " -o " + out, Err());
      if (refusal.empty()) {
        EXPECT_EQ(r.status, 0) << format << ": " << r.err;
        if (format != "c") {
          const std::string text = ReadFile(out);
          const std::string key = format == "yaml" ? e.name + ":" : "\"" + e.name + "\"";
          EXPECT_NE(text.find(key), std::string::npos) << format;
        }
      } else {
        EXPECT_EQ(r.status, 2) << format;
        EXPECT_EQ(r.err, "triadcal: error: " + refusal + "\n") << format;
        EXPECT_EQ(refusal.rfind(truth + ": " + e.name + ": ", 0), 0u) << refusal;
        EXPECT_FALSE(fs::exists(out)) << format;
        EXPECT_FALSE(fs::exists(Path(e.name + ".h"))) << format;
      }
    }
    if (!refusal.empty()) {
      ++refused;
      continue;
    }
    ++carried;
    if (!gyro) {
      EXPECT_LE(LargestDifference(truth, run), 1e-9);
      continue;
    }
    ++gyro_carried;
    // The json-matrix names the effect's parameters as the catalogue does.
    const nlohmann::json m = nlohmann::json::parse(ReadFile(Path(e.name + ".json-matrix")));
    const int o = LoadCalibration(truth).layout.offset(e.id);
    for (std::size_t q = 0; q < e.params.size(); ++q) {
      const nlohmann::json& p = m["gyro"]["effects"][e.name]["parameters"][e.params[q].name];
      ASSERT_TRUE(p.is_object()) << e.params[q].name;
      EXPECT_EQ(p["unit"], e.params[q].unit);
      EXPECT_NEAR(p["value"].get<double>(),
                  LoadCalibration(truth).theta[o + static_cast<int>(q)] / e.params[q].si_per_unit,
                  1e-12 * std::abs(TypicalValue(e, e.params[q], 175.8)));
    }
    double gyro_dps = 1e300;
    EXPECT_LE(LargestDifference(truth, run, &gyro_dps), 1e-9);
    EXPECT_LE(gyro_dps, 1e-9);
    // A fit with the effect: its OUT carries the effect's parameters, and so
    // does its export.
    for (const char* file : {"applied.csv", "cal.c", "cal.h", "fit.json"}) fs::remove(Path(file));
    const auto f =
        RunTriadcal("fit " + run + " --effects " + e.name + " -o " + Path("fit.json"), Err());
    ASSERT_EQ(f.status, 0) << f.err;
    ASSERT_TRUE(LoadCalibration(Path("fit.json")).layout.has(e.id));
    gyro_dps = 1e300;
    EXPECT_LE(LargestDifference(Path("fit.json"), run, &gyro_dps), 1e-9);
    EXPECT_LE(gyro_dps, 1e-9);
    for (const char* file : {"applied.csv", "cal.c", "cal.h"}) fs::remove(Path(file));
  }
  // thermal_drift, thermal_drift_temp, scale_asymmetry, cross_quadratic and
  // gyro_scale_asymmetry, gyro_nonlinearity
  EXPECT_GE(carried, 6);
  EXPECT_GE(gyro_carried, 2);
  EXPECT_GE(refused, 1);  // thermal_drift_quadratic
}

// The real run: the Ferraris six-position session, calibrated by `static`.
TEST_F(ExportTest, CMatchesApplyOnTheFerrarisRun) {
  const std::string yaml = std::string(TRIADCAL_SOURCE_DIR) + "/examples/ferraris/run.yaml";
  const std::string csv =
      ResolveDataPath(yaml, "shared:data/real/ferraris-six-position/annotated_session.csv");
  if (csv.empty() || !fs::exists(csv)) GTEST_SKIP() << "shared data folder absent";
  const auto s = RunTriadcal("static " + yaml + " -o " + Path("static.json"), Err());
  ASSERT_EQ(s.status, 0) << s.err;
  EXPECT_LE(LargestDifference(Path("static.json"), yaml), 1e-9);
}

// S a + b + diag(a) N a with a = W g0 is the readings model, every K_ij on.
TEST_F(ExportTest, MatrixFormIsTheReadingsModel) {
  Simulate(Scenario(""));
  for (const std::string format : {"json-matrix", "yaml"}) {
    const std::string out = Path("matrix." + format);
    const auto r = RunTriadcal(
        "export " + Path("sim/truth.json") + " --format " + format + " -o " + out, Err());
    ASSERT_EQ(r.status, 0) << r.err;
  }
  const nlohmann::json m = nlohmann::json::parse(ReadFile(Path("matrix.json-matrix")));
  EXPECT_TRUE(m.contains("provenance"));
  const std::string yaml = ReadFile(Path("matrix.yaml"));
  EXPECT_NE(yaml.find("S_mV_per_mps2:"), std::string::npos);
  EXPECT_NE(yaml.find("# provenance: {"), std::string::npos);

  const Calibration cal = LoadCalibration(Path("sim/truth.json"));
  const ModelConfig cfg = MakeModelConfig(RunDescription(), cal.layout);
  const double g0 = m["g0_mps2"].get<double>();
  for (const Eigen::Vector3d& W :
       {Eigen::Vector3d(0.3, -0.8, 0.52), Eigen::Vector3d(-1, 0.1, 0.2)}) {
    const Eigen::Vector3d z = Readings_mV(cfg, cal.theta.data(), W, SampleContext{});
    const Eigen::Vector3d a = W * g0;
    for (int i = 0; i < 3; ++i) {
      double zi = m["b_mV"][i].get<double>();
      double Na = 0.0;
      for (int j = 0; j < 3; ++j) {
        zi += m["S_mV_per_mps2"][i][j].get<double>() * a[j];
        Na += m["N_mV_per_mps2_sq"][i][j].get<double>() * a[j];
      }
      zi += a[i] * Na;
      EXPECT_NEAR(zi, z[i], 1e-9) << i;
    }
  }
}

// The labels follow the readings: a fit of a run read in counts exported as
// YAML, json-matrix and C names counts (counts/g, counts/s, ...), never mV, and
// its C code still gives what apply gives on that run.
TEST_F(ExportTest, LabelsFollowTheReadingsUnitOfACountsFit) {
  Simulate(Scenario(""));
  // The simulated readings, declared as counts (174 counts/g, as the nominal).
  const std::string counts = WriteText(
      "sim/counts.yaml",
      "data: run.csv\n"
      "bench: {lever_arm_mm: [138, 20, 20], angle_noise_arcsec: 15}\n"
      "triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500], noise_mV: 1}\n"
      "columns:\n"
      "  wx: {source: wx, unit: counts, counts_per_g: 174}\n"
      "  wy: {source: wy, unit: counts, counts_per_g: 174}\n"
      "  wz: {source: wz, unit: counts, counts_per_g: 174}\n");
  const std::string fit = Path("fit.json");
  auto r = RunTriadcal("fit " + counts + " --effects thermal_drift,scale_asymmetry -o " + fit,
                       Err());
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_EQ(nlohmann::json::parse(ReadFile(fit))["parameters"]["Kx"]["unit"], "counts/g");

  // Everything but the provenance (which quotes paths and the command line).
  auto without_provenance = [](const std::string& text) {
    std::string out, line;
    std::istringstream in(text);
    while (std::getline(in, line)) {
      if (line.find("provenance") == std::string::npos) out += line + "\n";
    }
    return out;
  };
  for (const std::string format : {"json-matrix", "yaml"}) {
    r = RunTriadcal("export " + fit + " --format " + format + " -o " + Path("m." + format), Err());
    ASSERT_EQ(r.status, 0) << r.err;
  }
  nlohmann::json m = nlohmann::json::parse(ReadFile(Path("m.json-matrix")));
  m.erase("provenance");
  const std::string json = m.dump();
  EXPECT_EQ(json.find("mV"), std::string::npos) << json;
  EXPECT_EQ(m["readings_unit"], "counts");
  EXPECT_TRUE(m.contains("S_counts_per_mps2")) << json;
  EXPECT_TRUE(m.contains("b_counts")) << json;
  EXPECT_TRUE(m.contains("S_inverse_mps2_per_counts")) << json;
  EXPECT_TRUE(m["in_g"].contains("S_counts_per_g")) << json;
  EXPECT_TRUE(m["effects"]["thermal_drift"].contains("rate_counts_per_s")) << json;
  EXPECT_TRUE(m["effects"]["scale_asymmetry"].contains("dK_counts_per_g")) << json;
  EXPECT_NE(m["model"].get<std::string>().find("z readings [counts]"), std::string::npos);

  const std::string yaml = without_provenance(ReadFile(Path("m.yaml")));
  EXPECT_EQ(yaml.find("mV"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("S_counts_per_mps2:"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("in_g:\n  S_counts_per_g:"), std::string::npos) << yaml;

  EXPECT_LE(LargestDifference(fit, counts), 1e-9);  // exports cal.c and cal.h
  const std::string h = without_provenance(ReadFile(Path("cal.h")));
  const std::string c = without_provenance(ReadFile(Path("cal.c")));
  EXPECT_EQ(h.find("mV"), std::string::npos) << h;
  EXPECT_EQ(c.find("mV"), std::string::npos) << c;
  EXPECT_NE(h.find("Raw readings z [counts]"), std::string::npos) << h;
  EXPECT_NE(h.find("_apply(const double z_counts[3]"), std::string::npos) << h;
  EXPECT_NE(c.find("Scale factors K_i [counts/g] and zero offsets W0_i [counts]"),
            std::string::npos)
      << c;
  EXPECT_NE(c.find("zero drift [counts/s]"), std::string::npos) << c;
}

TEST_F(ExportTest, BadOptions) {
  Simulate(Scenario(""));
  const std::string cal = Path("sim/truth.json");
  auto r = RunTriadcal("export " + cal + " --format fortran -o " + Path("x.f"), Err());
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "triadcal: error: --format: expected c, yaml or json-matrix, got 'fortran'\n");
  r = RunTriadcal("export " + cal + " --format c -o " + Path("cal.txt"), Err());
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err,
            "triadcal: error: -o: for --format c give NAME.c or NAME.h (both are "
            "written), got '" +
                Path("cal.txt") + "'\n");
  r = RunTriadcal("export " + cal + " --format c -o " + Path("my-cal.c"), Err());
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err,
            "triadcal: error: -o: file name 'my-cal' is not a C identifier (the "
            "function is NAME_apply); use --name\n");
  EXPECT_FALSE(fs::exists(Path("my-cal.c")));
  r = RunTriadcal("export " + cal + " --format c -o " + Path("my-cal.c") + " --name imu0", Err());
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(ReadFile(Path("my-cal.h")).find("void imu0_apply("), std::string::npos);
}

}  // namespace
}  // namespace triadcal

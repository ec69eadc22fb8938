// `triadcal apply` with the gyro (SPEC section 10): on a noise-free simulated
// run with every gyro parameter non-zero (a reversed z gyro, Earth's rate) the
// corrected rates omega_x omega_y omega_z are the bench's true input rate to
// 1e-9 deg/s; a calibration with the gyro on a run without one, and a run
// with the gyro under a calibration without it, give the accelerometer alone
// with exactly one warning line; the gyro's effects are applied and exported.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/io/file_util.h"
#include "core/model/gyro_model.h"
#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::RunTriadcal;

// Every gyro parameter non-zero; no noise anywhere (the angles, readings and
// rates are the model's), so what apply gives can be held to rounding.
const char kGyroTruth[] =
    "truth: {Kx: 171.5, Ky: 175.8, Kz: 174.8, W0x: 1504.2, W0y: 1498.0, W0z: 1502.5,\n"
    "        alpha_x: 16, beta_z: 26, gamma_y: 140, Kxy: -0.0012, Kzz: -0.0008,\n"
    "        dpsi: -33, dlambda2: -33, dx2: -7,\n"
    "        gyro.Kx: 1.004, gyro.Ky: 0.997, gyro.Kz: -1.002,\n"
    "        gyro.W0x: 0.31, gyro.W0y: -0.52, gyro.W0z: 0.2,\n"
    "        gyro.alpha_x: 12, gyro.alpha_y: -8, gyro.beta_x: 5, gyro.beta_z: 15,\n"
    "        gyro.gamma_y: -20, gyro.gamma_z: 7,\n"
    "        gyro.Gxx: 0.02, gyro.Gxy: 0.05, gyro.Gxz: -0.03, gyro.Gyx: 0.01, gyro.Gyy: -0.04,\n"
    "        gyro.Gyz: 0.02, gyro.Gzx: -0.01, gyro.Gzy: 0.03, gyro.Gzz: 0.06}\n";

std::string ScenarioText(bool gyro, const std::string& effects = "") {
  return std::string(
             "seed: 3\n"
             "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 20, "
             "rate_hz: 50}\n") +
         effects + (gyro ? kGyroTruth : "truth: {Kx: 171.5}\n") +
         "noise: {accel_mV: 0, angle_arcsec: 0" + (gyro ? ", gyro_dps: 0" : "") +
         "}\n"
         "run:\n"
         "  bench: {lever_arm_mm: [138, 20, 20], angle_noise_arcsec: 15" +
         (gyro ? ", latitude_deg: 48, heading_deg: 30" : "") +
         "}\n"
         "  triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, 1500], "
         "noise_mV: 2.0}\n" +
         (gyro ? "  gyro: {scale: [1, 1, -1], noise_dps: 0.05}\n" : "");
}

// The CSV of apply: its header and its columns by name.
struct Applied {
  std::vector<std::string> header;
  std::map<std::string, std::vector<double>> columns;
};

Applied ReadApplied(const std::string& path) {
  Applied a;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (a.header.empty()) {
      a.header = cells;
      continue;
    }
    for (std::size_t i = 0; i < cells.size() && i < a.header.size(); ++i) {
      a.columns[a.header[i]].push_back(std::stod(cells[i]));
    }
  }
  return a;
}

int CountLines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

class CliGyroApply : public testing_fixtures::TempDirTest {
 protected:
  std::string Err() const { return Path("err.txt"); }

  // Simulates the scenario into DIR; returns DIR/run.yaml.
  std::string Simulate(bool gyro, const std::string& dir, const std::string& effects = "") {
    const std::string scen = WriteText(dir + ".yaml", ScenarioText(gyro, effects));
    const auto r = RunTriadcal("simulate " + scen + " -o " + Path(dir), Err());
    EXPECT_EQ(r.status, 0) << r.err;
    return Path(dir + "/run.yaml");
  }

  // `triadcal apply CAL RUN`: its CSV and stderr.
  Applied Apply(const std::string& cal, const std::string& run, const std::string& out,
                std::string* err) {
    const auto r = RunTriadcal("apply " + cal + " " + run + " -o " + Path(out), Err());
    EXPECT_EQ(r.status, 0) << r.err;
    *err = r.err;
    return ReadApplied(Path(out));
  }
};

TEST_F(CliGyroApply, CorrectedRatesAreTheTrueInputRate) {
  const std::string run = Simulate(true, "sim");
  std::string err;
  const Applied a = Apply(Path("sim/truth.json"), run, "w.csv", &err);
  EXPECT_EQ(err, "");
  ASSERT_GE(a.header.size(), 7u);
  EXPECT_EQ(std::vector<std::string>(a.header.begin(), a.header.begin() + 7),
            (std::vector<std::string>{"t", "Wx", "Wy", "Wz", "omega_x", "omega_y", "omega_z"}));
  const std::string text = ReadFile(Path("w.csv"));
  EXPECT_NE(text.find("# omega = angular rate in the triad frame [deg/s]"), std::string::npos);

  // The truth: the bench's input rate at its true angles (gyro_model.h).
  Scenario s = LoadScenario(Path("sim.yaml"));
  const ModelConfig cfg = TruthModelConfig(s);
  ASSERT_TRUE(cfg.layout.has_gyro());
  ASSERT_FALSE(cfg.earth_rate_L.isZero());
  const std::vector<double>& t = a.columns.at("t");
  ASSERT_EQ(t.size(), s.profile.NumSamples());
  double worst_dps = 0.0, largest_dps = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    const BenchAngles<double> bench = s.profile.At(t[k]);
    const BenchMotion<double> m = ComputeBenchMotion(cfg, s.truth.data(), bench);
    const Eigen::Vector3d w_dps = GyroInputRate_2(cfg, s.truth.data(), bench, m.C_L2) / kDegToRad;
    const std::vector<double>* omega[3] = {&a.columns.at("omega_x"), &a.columns.at("omega_y"),
                                           &a.columns.at("omega_z")};
    for (int i = 0; i < 3; ++i) {
      worst_dps = std::max(worst_dps, std::abs((*omega[i])[k] - w_dps[i]));
      largest_dps = std::max(largest_dps, std::abs(w_dps[i]));
    }
  }
  // (The raw readings differ from the rate by the biases alone by 0.2 deg/s.)
  EXPECT_LE(worst_dps, 1e-9);
  EXPECT_GT(largest_dps, 10.0);  // the bench turns
}

// The gyro's effects (gyro_model.h) injected by simulate: apply inverts them
// with the rest of the readings model, to rounding; export carries them in
// every form (its C agrees with apply to 1e-9 deg/s:
// ExportTest.EverySensorAndGyroStageEffectIsCarriedOrRefusedByName).
const char kGyroEffects[] =
    "effects: {gyro_scale_asymmetry: {dKx: 3000, dKy: -2000, dKz: 1500},\n"
    "          gyro_nonlinearity: {k2_x: 0.3, k2_y: -0.2, k2_z: 0.5}}\n";

TEST_F(CliGyroApply, GyroEffectsAreAppliedAndExported) {
  const std::string run = Simulate(true, "sim", kGyroEffects);
  std::string err;
  const Applied a = Apply(Path("sim/truth.json"), run, "w.csv", &err);
  EXPECT_EQ(err, "");
  Scenario s = LoadScenario(Path("sim.yaml"));
  const ModelConfig cfg = TruthModelConfig(s);
  ASSERT_TRUE(cfg.layout.has(Effect::kGyroScaleAsymmetry));
  ASSERT_TRUE(cfg.layout.has(Effect::kGyroNonlinearity));
  const std::vector<double>& t = a.columns.at("t");
  ASSERT_EQ(t.size(), s.profile.NumSamples());
  double worst_dps = 0.0, worst_without_dps = 0.0;
  // The same readings corrected as if the effects were not there.
  Eigen::VectorXd plain = s.truth;
  for (Effect e : {Effect::kGyroScaleAsymmetry, Effect::kGyroNonlinearity}) {
    for (int q = 0; q < 3; ++q) plain[cfg.layout.offset(e) + q] = 0.0;
  }
  for (std::size_t k = 0; k < t.size(); ++k) {
    const BenchAngles<double> bench = s.profile.At(t[k]);
    const BenchMotion<double> m = ComputeBenchMotion(cfg, s.truth.data(), bench);
    const Eigen::Vector3d w = GyroInputRate_2(cfg, s.truth.data(), bench, m.C_L2);
    const Eigen::Vector3d W = SpecificForce_g(cfg, m.C_L2,
                                              MotionOfPoint(m, LeverArm_m(cfg, s.truth.data())).a_L);
    const Eigen::Vector3d G = GyroReadings(cfg, s.truth.data(), w, W);
    const Eigen::Vector3d w_plain = GyroRateFromReadings(cfg, plain.data(), G, W);
    const std::vector<double>* omega[3] = {&a.columns.at("omega_x"), &a.columns.at("omega_y"),
                                           &a.columns.at("omega_z")};
    for (int i = 0; i < 3; ++i) {
      worst_dps = std::max(worst_dps, std::abs((*omega[i])[k] - w[i] / kDegToRad));
      worst_without_dps = std::max(worst_without_dps, std::abs(w_plain[i] - w[i]) / kDegToRad);
    }
  }
  std::printf("apply with the gyro effects: worst %.3g deg/s (without them %.3g deg/s)\n",
              worst_dps, worst_without_dps);
  EXPECT_LE(worst_dps, 1e-9);
  EXPECT_GT(worst_without_dps, 0.1);  // the effects matter at this size
  for (const auto& [format, file] : std::vector<std::pair<std::string, std::string>>{
           {"c", "cal.c"}, {"yaml", "cal.yaml"}, {"json-matrix", "cal.json"}}) {
    const auto r =
        RunTriadcal("export " + Path("sim/truth.json") + " --format " + format + " -o " +
                        Path(file),
                    Err());
    EXPECT_EQ(r.status, 0) << format << ": " << r.err;
    const std::string text = ReadFile(Path(file));
    if (format == "c") {
      // The C names neither effect (its constants are kGyroAsymmetry and kGyroK2).
      EXPECT_NE(text.find("static const int kGyroHasNonlinearity = 1;"), std::string::npos);
      continue;
    }
    for (const char* effect : {"gyro_scale_asymmetry", "gyro_nonlinearity"}) {
      EXPECT_NE(text.find(effect), std::string::npos) << format << " " << effect;
    }
  }
}

TEST_F(CliGyroApply, CalibrationWithTheGyroOnARunWithoutOne) {
  Simulate(true, "gyro");
  const std::string plain = Simulate(false, "plain");
  std::string with_gyro_err, without_err;
  const Applied with_gyro = Apply(Path("gyro/truth.json"), plain, "a.csv", &with_gyro_err);
  // The same calibration without its gyro keys: the accelerometer's result.
  nlohmann::json cal = nlohmann::json::parse(ReadFile(Path("gyro/truth.json")));
  for (auto it = cal["parameters"].begin(); it != cal["parameters"].end();) {
    it = it.key().rfind("gyro.", 0) == 0 ? cal["parameters"].erase(it) : std::next(it);
  }
  WriteText("accel_only.json", cal.dump(2));
  const Applied without = Apply(Path("accel_only.json"), plain, "b.csv", &without_err);
  EXPECT_EQ(without_err, "");
  EXPECT_EQ(CountLines(with_gyro_err), 1) << with_gyro_err;
  EXPECT_EQ(with_gyro_err, "triadcal: warning: " + plain + ": the calibration " +
                               Path("gyro/truth.json") +
                               " has the gyro (gyro.*), but the run has no gyro readings (gx gy "
                               "gz, read with a gyro block in run.yaml): accelerometer only\n");
  EXPECT_EQ(with_gyro.header, without.header);
  EXPECT_EQ(with_gyro.header,
            (std::vector<std::string>{"t", "Wx", "Wy", "Wz", "lambda1", "lambda2"}));
  EXPECT_EQ(with_gyro.columns, without.columns);
}

TEST_F(CliGyroApply, RunWithTheGyroUnderACalibrationWithoutIt) {
  const std::string run = Simulate(true, "sim");
  nlohmann::json cal = nlohmann::json::parse(ReadFile(Path("sim/truth.json")));
  for (auto it = cal["parameters"].begin(); it != cal["parameters"].end();) {
    it = it.key().rfind("gyro.", 0) == 0 ? cal["parameters"].erase(it) : std::next(it);
  }
  const std::string accel_only = WriteText("accel_only.json", cal.dump(2));
  std::string err, gyro_err;
  const Applied a = Apply(accel_only, run, "a.csv", &err);
  EXPECT_EQ(CountLines(err), 1) << err;
  EXPECT_EQ(err, "triadcal: warning: " + run + ": gx gy gz not corrected: the calibration " +
                     accel_only + " has no gyro parameters (gyro.*): accelerometer only\n");
  EXPECT_EQ(a.header, (std::vector<std::string>{"t", "Wx", "Wy", "Wz", "lambda1", "lambda2"}));
  // The accelerometer's columns are those the full calibration gives.
  const Applied full = Apply(Path("sim/truth.json"), run, "b.csv", &gyro_err);
  for (const char* c : {"t", "Wx", "Wy", "Wz", "lambda1", "lambda2"}) {
    EXPECT_EQ(a.columns.at(c), full.columns.at(c)) << c;
  }
}

// A calibration with part of the gyro, a gyro scale of 0, an unknown gyro
// name, or a gyro calibrated in rad/s applied to deg/s: one line, exit 2.
TEST_F(CliGyroApply, BadGyroCalibrations) {
  const std::string run = Simulate(true, "sim");
  const nlohmann::json truth = nlohmann::json::parse(ReadFile(Path("sim/truth.json")));
  const std::string c = Path("c.json");
  auto expect = [&](const nlohmann::json& cal, const std::string& message) {
    WriteText("c.json", cal.dump(2));
    const auto r = RunTriadcal("apply " + c + " " + run + " -o " + Path("w.csv"), Err());
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_EQ(r.err, "triadcal: error: " + c + ": " + message + "\n");
    EXPECT_FALSE(std::filesystem::exists(Path("w.csv")));
  };
  nlohmann::json cal = truth;
  cal["parameters"].erase("gyro.Gyz");
  expect(cal,
         "parameters.gyro.Gyz: missing (gyro.Kx is given: a calibration with the gyro needs its "
         "21 parameters gyro.Kx..gyro.Gzz, SPEC section 10)");
  cal = truth;
  cal["parameters"]["gyro.Ky"] = 0;
  expect(cal,
         "parameters.gyro.Ky: 0: a gyro scale factor must not be 0 (readings per deg/s; "
         "nominal 1)");
  cal = truth;
  cal["parameters"]["gyro.bogus"] = 1;
  expect(cal,
         "parameters.gyro.bogus: unknown gyro parameter (the gyro's are gyro.Kx ... gyro.Gzz, "
         "SPEC section 10 and docs/file-formats.md)");
  cal = truth;
  cal["parameters"]["gyro.Kx"] = 1.004 / kDegToRad;
  expect(cal, "parameters.gyro.Kx: 57.52 is 57.52 times above the run's nominal gyro scale 1 (" +
                  run +
                  ": gyro.scale; bound: a factor 10): a gyro calibrated in rad/s applied to "
                  "deg/s, or the calibration of another sensor?");
}

}  // namespace
}  // namespace triadcal

// Applying a calibration (core/model/apply_calibration.h, `triadcal apply`): the
// convention forward = readings model (paper eq. 1), apply = its exact
// inverse, tested as a round trip W -> readings -> W in memory and through
// the files (the OUT formats of fit, filter, static and truth.json); bad
// calibration files with their one-line errors; the gyro (SPEC section 10) as
// a round trip rate -> readings -> rate with W from the accelerometer's
// inverse, and a calibration file read with and without its gyro keys.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/calibration_io.h"
#include "core/model/bench_model.h"
#include "core/model/errors.h"
#include "core/model/gyro_model.h"
#include "core/model/mounting.h"
#include "tests/temp_dir_test.h"
#include "core/io/file_util.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "core/io/run_io.h"
#include "core/model/apply_calibration.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

class ApplyTest : public testing_fixtures::TempDirTest {
 protected:
  std::string Write(const std::string& name, const std::string& text) const {
    return WriteText(name, text);
  }
};

// A calibration with every sensor-stage parameter non-zero, in file units.
NamedValues CalibrationValues() {
  return {{"Kx", 171.5},      {"Ky", 175.8},         {"Kz", 174.8},
          {"W0x", 1504.2},    {"W0y", 1500.2},       {"W0z", 1495.5},
          {"alpha_x", 16},    {"alpha_y", -32},      {"beta_x", 11},
          {"beta_z", 26},     {"gamma_y", 140},      {"gamma_z", 64},
          {"Kxx", 2e-3},      {"Kxy", -1e-3},        {"Kxz", 5e-4},
          {"Kyx", 1.5e-3},    {"Kyy", -2e-3},        {"Kyz", 1e-3},
          {"Kzx", -5e-4},     {"Kzy", 2.5e-3},       {"Kzz", 1e-3},
          {"dpsi", -33},      {"dtheta_c", 43},      {"dlambda2", -33},
          {"dx2", -7},        {"dy2", 16},           {"dz2", 4},
          {"scale_asymmetry.dKx", 0.3}, {"scale_asymmetry.dKy", -0.2},
          {"scale_asymmetry.dKz", 0.1}, {"thermal_drift.rate_x", 0.5},
          {"thermal_drift.rate_y", -0.3}, {"thermal_drift.rate_z", 0.2}};
}

ParameterLayout CalibrationLayout() {
  return ParameterLayout({Effect::kScaleAsymmetry, Effect::kThermalDrift});
}

Eigen::VectorXd CalibrationTheta() {
  const ParameterLayout layout = CalibrationLayout();
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(layout.size());
  SetFromFileUnits(layout, CalibrationValues(), &theta);
  return theta;
}

// Known specific forces (up to 2 g, every sign) and the readings the forward
// model gives for them.
struct Truth {
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> W;
  RunData data;
};

Truth MakeTruth(const ParameterLayout& layout, const Eigen::VectorXd& theta, int n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  ModelConfig cfg;
  cfg.layout = layout;
  Truth tr;
  for (int k = 0; k < n; ++k) {
    const double t = 0.01 * k;
    const Eigen::Vector3d W(u(rng), u(rng), u(rng));
    const Eigen::Vector3d z = Readings_mV(cfg, theta.data(), W, SampleContext{t, 0.0});
    tr.W.push_back(W);
    tr.data.t_s.push_back(t);
    for (int i = 0; i < 2; ++i) tr.data.lambda_rad[i].push_back(0.1 * i + 1e-3 * k);
    for (int i = 0; i < 3; ++i) tr.data.w_mV[i].push_back(z[i]);
  }
  return tr;
}

// Readings a bench could give: W turns with the recorded angles (its direction
// moves by at most |d lambda1| + |d lambda2|) and its size goes from 1 to 2 g
// slowly, so the run passes the angle-unit plausibility checks of run_io.
Truth MakeBenchTruth(const ParameterLayout& layout, const Eigen::VectorXd& theta, int n) {
  ModelConfig cfg;
  cfg.layout = layout;
  Truth tr;
  for (int k = 0; k < n; ++k) {
    const double t = 0.01 * k;
    const double a = 0.1 + 0.05 * k, b = 0.2 + 0.03 * k;
    const double size_g = 1.5 + 0.5 * std::sin(2.0 * kPi * k / n);
    const Eigen::Vector3d W =
        size_g * Eigen::Vector3d(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b));
    const Eigen::Vector3d z = Readings_mV(cfg, theta.data(), W, SampleContext{t, 0.0});
    tr.W.push_back(W);
    tr.data.t_s.push_back(t);
    tr.data.lambda_rad[0].push_back(a);
    tr.data.lambda_rad[1].push_back(b);
    for (int i = 0; i < 3; ++i) tr.data.w_mV[i].push_back(z[i]);
  }
  return tr;
}

double MaxError(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double m = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) m = std::max(m, (a[k] - b[k]).cwiseAbs().maxCoeff());
  return m;
}

TEST(ApplyRoundTrip, InverseOfTheReadingsModelInMemory) {
  Calibration cal;
  cal.layout = CalibrationLayout();
  cal.theta = CalibrationTheta();
  const Truth tr = MakeTruth(cal.layout, cal.theta, 2000);
  RunDescription run;
  const std::vector<Eigen::Vector3d> W = ApplyCalibration(cal, run, tr.data);
  ASSERT_EQ(W.size(), tr.W.size());
  EXPECT_LT(MaxError(W, tr.W), 1e-12);
}

// The gyro block of a calibration in file units: every parameter non-zero, a
// reversed z gyro.
NamedValues GyroValues() {
  return {{"gyro.Kx", 1.004},     {"gyro.Ky", 0.997},     {"gyro.Kz", -1.002},
          {"gyro.W0x", 0.31},     {"gyro.W0y", -0.52},    {"gyro.W0z", 0.2},
          {"gyro.alpha_x", 12},   {"gyro.alpha_y", -8},   {"gyro.beta_x", 5},
          {"gyro.beta_z", 15},    {"gyro.gamma_y", -20},  {"gyro.gamma_z", 7},
          {"gyro.Gxx", 0.02},     {"gyro.Gxy", 0.05},     {"gyro.Gxz", -0.03},
          {"gyro.Gyx", 0.01},     {"gyro.Gyy", -0.04},    {"gyro.Gyz", 0.02},
          {"gyro.Gzx", -0.01},    {"gyro.Gzy", 0.03},     {"gyro.Gzz", 0.06}};
}

Calibration GyroCalibration() {
  Calibration cal;
  cal.layout = CalibrationLayout().WithGyro(true);
  cal.theta = Eigen::VectorXd::Zero(cal.layout.size());
  NamedValues v = CalibrationValues();
  for (const auto& [name, value] : GyroValues()) v[name] = value;
  SetFromFileUnits(cal.layout, v, &cal.theta);
  return cal;
}

// Gyro readings of known rates (up to 300 deg/s) at the specific forces of
// tr, added to tr.data; the rates [rad/s].
std::vector<Eigen::Vector3d> AddGyroReadings(const Calibration& cal, Truth* tr) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-300.0 * kDegToRad, 300.0 * kDegToRad);
  ModelConfig cfg;
  cfg.layout = cal.layout;
  std::vector<Eigen::Vector3d> rates;
  for (std::size_t k = 0; k < tr->W.size(); ++k) {
    const Eigen::Vector3d w(u(rng), u(rng), u(rng));
    const Eigen::Vector3d g = GyroReadings(cfg, cal.theta.data(), w, tr->W[k]);
    rates.push_back(w);
    for (int i = 0; i < 3; ++i) tr->data.gyro_rad_s[i].push_back(g[i]);
  }
  return rates;
}

TEST(ApplyRoundTrip, GyroInverseWithTheCorrectedSpecificForce) {
  const Calibration cal = GyroCalibration();
  ASSERT_TRUE(cal.layout.has_gyro());
  Truth tr = MakeTruth(cal.layout, cal.theta, 2000);
  const std::vector<Eigen::Vector3d> rates = AddGyroReadings(cal, &tr);
  RunDescription run;
  const std::vector<Eigen::Vector3d> W = ApplyCalibration(cal, run, tr.data);
  EXPECT_LT(MaxError(W, tr.W), 1e-12);  // the gyro block leaves the accelerometer alone
  const std::vector<Eigen::Vector3d> omega = ApplyGyroCalibration(cal, run, tr.data, W);
  ASSERT_EQ(omega.size(), rates.size());
  EXPECT_LT(MaxError(omega, rates), 1e-12);  // rad/s
  // W matters: with W = 0 the g-sensitivity (0.06 (deg/s)/g) is left in.
  const std::vector<Eigen::Vector3d> no_W = ApplyGyroCalibration(
      cal, run, tr.data, std::vector<Eigen::Vector3d>(W.size(), Eigen::Vector3d::Zero()));
  EXPECT_GT(MaxError(no_W, rates), 1e-2 * kDegToRad);
}

// A calibration in the IMU's own axes (a joint fit's "axes": "imu") with the
// gyro, applied to a run whose mounting turns the IMU: the rates come out in
// the platform's axes, as the specific force does.
TEST(ApplyRoundTrip, GyroInTheImuAxesThroughTheMounting) {
  const Calibration imu = GyroCalibration();
  RunDescription run;
  const int source[3] = {1, 2, 0};
  const double sign[3] = {-1.0, 1.0, -1.0};
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    run.axis_source[i] = source[i];
    run.axis_sign[i] = sign[i];
    P(i, source[i]) = sign[i];
  }
  // The IMU's readings of known platform W and rates, then mounted as
  // run_io does: platform reading i = sign_i * IMU reading source_i.
  Truth tr = MakeTruth(imu.layout, imu.theta, 300);
  std::vector<Eigen::Vector3d> W_p, w_p;
  ModelConfig cfg;
  cfg.layout = imu.layout;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  RunData mounted;
  for (std::size_t k = 0; k < tr.W.size(); ++k) {
    const Eigen::Vector3d Wp = tr.W[k], wp(u(rng), u(rng), u(rng));
    const Eigen::Vector3d z =
        P * Readings_mV(cfg, imu.theta.data(), Eigen::Vector3d(P.transpose() * Wp),
                        SampleContext{tr.data.t_s[k], 0.0});
    const Eigen::Vector3d g =
        P * GyroReadings(cfg, imu.theta.data(), Eigen::Vector3d(P.transpose() * wp),
                         Eigen::Vector3d(P.transpose() * Wp));
    mounted.t_s.push_back(tr.data.t_s[k]);
    for (int i = 0; i < 3; ++i) {
      mounted.w_mV[i].push_back(z[i]);
      mounted.gyro_rad_s[i].push_back(g[i]);
    }
    W_p.push_back(Wp);
    w_p.push_back(wp);
  }
  Calibration cal = imu;
  cal.imu_axes = true;
  const std::vector<Eigen::Vector3d> W = ApplyCalibration(cal, run, mounted);
  EXPECT_LT(MaxError(W, W_p), 1e-12);
  EXPECT_LT(MaxError(ApplyGyroCalibration(cal, run, mounted, W), w_p), 1e-12);
  // Without the mounting map the rates would be wrong.
  cal.imu_axes = false;
  EXPECT_GT(MaxError(ApplyGyroCalibration(cal, run, mounted, W), w_p), 1e-3);
}

TEST(ApplyRoundTrip, GyroNeedsTheGyroInBoth) {
  Calibration cal = GyroCalibration();
  cal.path = "cal.json";
  Truth tr = MakeTruth(cal.layout, cal.theta, 5);
  RunDescription run;
  run.yaml_path = "run.yaml";
  try {
    ApplyGyroCalibration(cal, run, tr.data, tr.W);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "run.yaml: no gyro readings (gx gy gz, read with a gyro block)");
  }
  AddGyroReadings(cal, &tr);
  Calibration plain;
  plain.path = "plain.json";
  plain.layout = CalibrationLayout();
  plain.theta = CalibrationTheta();
  try {
    ApplyGyroCalibration(plain, run, tr.data, tr.W);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "plain.json: the calibration has no gyro parameters (gyro.Kx..gyro.Gzz)");
  }
}

// The OUT of a fit with the gyro: the layout has the gyro block and its values
// (SI inside); without the gyro keys, the layout is the one it always was.
TEST(CalibrationFile, ReadWithAndWithoutTheGyro) {
  const Calibration expected = GyroCalibration();
  nlohmann::json p;
  for (int i = 0; i < expected.layout.size(); ++i) {
    const ParameterInfo& info = expected.layout.info(i);
    const double v = expected.theta[i] / info.si_per_unit;
    p[info.name] = {{"value", v}, {"sigma", 0.1}, {"unit", info.unit}};
  }
  const nlohmann::json root = {{"command", "fit"}, {"parameters", p}};
  const Calibration with_gyro = CalibrationFromJson(root, "fit.json");
  ASSERT_TRUE(with_gyro.layout.has_gyro());
  EXPECT_EQ(with_gyro.layout.size(), expected.layout.size());
  const int g = with_gyro.layout.gyro_offset();
  EXPECT_EQ(with_gyro.layout.info(g).name, "gyro.Kx");
  for (int i = 0; i < expected.layout.size(); ++i) {  // (effects in the catalogue's order)
    const std::string& name = expected.layout.info(i).name;
    const int j = with_gyro.layout.IndexOf(name);
    ASSERT_GE(j, 0) << name;
    EXPECT_NEAR(with_gyro.theta[j], expected.theta[i], 1e-15 * std::abs(expected.theta[i])) << name;
  }
  EXPECT_DOUBLE_EQ(with_gyro.theta[g + kGW0x], 0.31 * kDegToRad);
  EXPECT_DOUBLE_EQ(with_gyro.theta[g + kGBetaZ], 15 * kArcminToRad);
  EXPECT_DOUBLE_EQ(with_gyro.theta[g + kGGzz], 0.06 * kDegToRad);
  EXPECT_EQ(with_gyro.readings_unit, "mV");

  nlohmann::json plain = root;
  for (const auto& [name, value] : GyroValues()) plain["parameters"].erase(name);
  const Calibration without = CalibrationFromJson(plain, "fit.json");
  EXPECT_FALSE(without.layout.has_gyro());
  EXPECT_EQ(without.layout.size(), CalibrationLayout().size());
  EXPECT_EQ(without.theta, with_gyro.theta.head(without.layout.size()));
}

std::string ParametersJsonText(const std::string& wrap) {
  const ParameterLayout layout = CalibrationLayout();
  const NamedValues v = CalibrationValues();
  nlohmann::json p;
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& info = layout.info(i);
    p[info.name] = {{"value", v.at(info.name)}, {"sigma", 0.1}, {"unit", info.unit}};
  }
  nlohmann::json root;
  if (wrap == "fit") {
    root = {{"command", "fit"}, {"parameters", p}};
  } else {  // filter: the rts section is used, the ekf one ignored
    nlohmann::json wrong = p;
    wrong["Kx"]["value"] = 1.0;
    root = {{"command", "filter"}, {"ekf", {{"parameters", wrong}}}, {"rts", {{"parameters", p}}}};
  }
  return root.dump(2);
}

// truth.json: plain values, effect parameters as effect.name_unit.
std::string TruthJsonText() {
  const ParameterLayout layout = CalibrationLayout();
  const NamedValues v = CalibrationValues();
  nlohmann::json p;
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& info = layout.info(i);
    std::string key = info.name;
    if (info.effect) {
      const EffectSpec& e = GetEffectSpec(*info.effect);
      key = e.name + "." + UnitSuffixedKey(e.params[i - layout.offset(*info.effect)]);
    }
    p[key] = v.at(info.name);
  }
  p["unknown_key"] = 3;  // ignored, as every reader of a truth file does
  return nlohmann::json{{"parameters", p}}.dump(2);
}

std::vector<Eigen::Vector3d> ReadCorrectedCsv(const std::string& path, std::vector<double>* t,
                                              std::vector<std::string>* header) {
  std::ifstream in(path);
  std::string line;
  std::vector<Eigen::Vector3d> W;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string field;
    std::vector<std::string> fields;
    while (std::getline(ss, field, ',')) fields.push_back(field);
    if (header->empty()) {
      *header = fields;
      continue;
    }
    t->push_back(std::strtod(fields[0].c_str(), nullptr));
    W.emplace_back(std::strtod(fields[1].c_str(), nullptr), std::strtod(fields[2].c_str(), nullptr),
                   std::strtod(fields[3].c_str(), nullptr));
  }
  return W;
}

int RunCli(const std::string& args, const std::string& err) {
  return std::system((std::string(TRIADCAL_BIN) + " " + args + " > /dev/null 2> " + err).c_str());
}

TEST_F(ApplyTest, RoundTripThroughTheFilesOfEveryCommand) {
  const Truth tr = MakeBenchTruth(CalibrationLayout(), CalibrationTheta(), 500);
  WriteRunCsv(tr.data, Path("run.csv"), "readings of known specific forces");
  const std::string run = Write("run.yaml", "data: run.csv\nconstraints: []\n");
  const std::string err = Path("err.txt");
  for (const std::string kind : {"fit", "filter", "truth"}) {
    // One output per calibration: apply will not replace results of other inputs.
    const std::string out = Path("corrected_" + kind + ".csv");
    const std::string cal =
        Write(kind + ".json", kind == "truth" ? TruthJsonText() : ParametersJsonText(kind));
    ASSERT_EQ(RunCli("apply " + cal + " " + run + " -o " + out, err), 0) << ReadFile(err);
    std::vector<double> t;
    std::vector<std::string> header;
    const std::vector<Eigen::Vector3d> W = ReadCorrectedCsv(out, &t, &header);
    EXPECT_EQ(header, (std::vector<std::string>{"t", "Wx", "Wy", "Wz", "lambda1", "lambda2"}))
        << kind;
    ASSERT_EQ(W.size(), tr.W.size()) << kind;
    for (std::size_t k = 0; k < t.size(); ++k) ASSERT_EQ(t[k], tr.data.t_s[k]);
    EXPECT_LT(MaxError(W, tr.W), 1e-12) << kind;
  }
}

TEST_F(ApplyTest, BadCalibrationFilesGiveOneLine) {
  const Truth tr = MakeTruth(CalibrationLayout(), CalibrationTheta(), 20);
  WriteRunCsv(tr.data, Path("run.csv"), "");
  const std::string run = Write("run.yaml", "data: run.csv\nconstraints: []\n");
  const std::string out = Path("corrected.csv"), err = Path("err.txt");
  auto error_of = [&](const std::string& text) {
    const std::string cal = Write("cal.json", text);
    EXPECT_EQ(RunCli("apply " + cal + " " + run + " -o " + out, err) >> 8, 2) << text;
    EXPECT_FALSE(fs::exists(out)) << text;
    const std::string e = ReadFile(err);
    EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
    return e;
  };
  const std::string f = Path("cal.json");
  EXPECT_EQ(error_of("{\"parameters\": "),
            "triadcal: error: " + f +
                ": not valid JSON: line 1, column 16: syntax error while parsing value - "
                "unexpected end of input; expected '[', '{', or a literal\n");
  EXPECT_EQ(error_of("Kx: 174\n"),
            "triadcal: error: " + f +
                ": not valid JSON: line 1, column 1: syntax error while parsing value - invalid "
                "literal; last read: 'K' (a calibration is a JSON object, the OUT of fit, static "
                "or diagnose; this file does not start with '{')\n");
  EXPECT_EQ(error_of("{\"ekf\": {}}"),
            "triadcal: error: " + f +
                ": parameters: missing (expected an OUT of fit, static, diagnose, filter "
                "(\"rts\"), compare (\"batch\") or a truth.json)\n");
  nlohmann::json j = nlohmann::json::parse(ParametersJsonText("fit"));
  j["parameters"].erase("Kyz");
  EXPECT_EQ(error_of(j.dump()),
            "triadcal: error: " + f +
                ": parameters.Kyz: missing (a calibration needs the 21 sensor parameters Kx..Kzz "
                "of docs/file-formats.md, and every parameter of an effect it names)\n");
  j = nlohmann::json::parse(ParametersJsonText("fit"));
  j["parameters"]["gamma_y"]["unit"] = "deg";
  EXPECT_EQ(error_of(j.dump()), "triadcal: error: " + f +
                                    ": parameters.gamma_y: unit \"deg\", expected \"arcmin\" "
                                    "(docs/file-formats.md)\n");
  j = nlohmann::json::parse(ParametersJsonText("fit"));
  j["parameters"]["W0x"]["value"] = "1500";
  EXPECT_EQ(error_of(j.dump()),
            "triadcal: error: " + f + ": parameters.W0x: value is not a number: \"1500\"\n");
  j = nlohmann::json::parse(ParametersJsonText("fit"));
  j["parameters"].erase("thermal_drift.rate_y");
  EXPECT_EQ(error_of(j.dump()),
            "triadcal: error: " + f +
                ": parameters.thermal_drift.rate_y: missing (a calibration needs the 21 sensor "
                "parameters Kx..Kzz of docs/file-formats.md, and every parameter of an effect it "
                "names)\n");
  j = nlohmann::json::parse(ParametersJsonText("fit"));
  j["parameters"]["Ky"]["value"] = 0;
  EXPECT_EQ(error_of(j.dump()),
            "triadcal: error: " + f +
                ": parameters.Ky: 0 mV/g: a scale factor must be > 0 (an axis that reads -1 g "
                "when it points up belongs in the run's mounting.axes)\n");
  // The run is checked too: a missing run.yaml.
  EXPECT_EQ(RunCli("apply " + Write("ok.json", ParametersJsonText("fit")) + " " +
                       Path("none.yaml") + " -o " + out,
                   err) >> 8,
            2);
  EXPECT_EQ(ReadFile(err), "triadcal: error: " + Path("none.yaml") +
                               ": cannot read (no such file or not readable)\n");
  EXPECT_FALSE(fs::exists(out));
}

// static -> apply: the calibrated specific force of each still position is
// its up direction, to the noise of the fit.
TEST_F(ApplyTest, StaticOutAppliedToItsOwnRun) {
  ModelConfig cfg;
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(kNumBaseParams);
  SetFromFileUnits(ParameterLayout(),
                   {{"Kx", 2050}, {"Ky", 2040}, {"Kz", 2100}, {"W0x", -9}, {"W0y", -58},
                    {"W0z", -32}, {"alpha_x", -27}, {"gamma_z", -80}, {"beta_z", 30}},
                   &theta);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::string csv = "t,part,ax,ay,az\n";
  const char* labels[6] = {"x_p", "x_a", "y_p", "y_a", "z_p", "z_a"};
  int k = 0;
  for (int p = 0; p < 6; ++p) {
    Eigen::Vector3d up = Eigen::Vector3d::Zero();
    up[p / 2] = p % 2 ? -1.0 : 1.0;
    const Eigen::Vector3d z = Readings_mV(cfg, theta.data(), up, SampleContext{});
    for (int j = 0; j < 400; ++j, ++k) {
      const bool moving = j < 100;  // 1 s of motion before each hold
      csv += FormatDouble(0.01 * k) + "," + (moving ? "move" : labels[p]);
      for (int i = 0; i < 3; ++i) {
        csv += "," + FormatDouble(z[i] + 7.0 * normal(rng) + (moving ? 3000.0 * std::sin(0.05 * j) : 0.0));
      }
      csv += "\n";
    }
  }
  Write("s.csv", csv);
  const std::string run = Write(
      "run.yaml",
      "data: s.csv\ncolumns: {lambda1: {value: 0}, lambda2: {value: 0}, wx: ax, wy: ay, wz: az, "
      "label: part}\ntriad: {scale_mV_per_g: [2048, 2048, 2048], bias_mV: [0, 0, 0], noise_mV: "
      "7}\nconstraints: []\n");
  const std::string err = Path("err.txt");
  ASSERT_EQ(RunCli("static " + run + " -o " + Path("static.json"), err), 0) << ReadFile(err);
  ASSERT_EQ(RunCli("apply " + Path("static.json") + " " + run + " -o " + Path("w.csv"), err), 0)
      << ReadFile(err);
  std::ifstream in(Path("w.csv"));
  std::string line;
  std::map<std::string, Eigen::Vector3d> sum;
  std::map<std::string, int> count;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 't') continue;
    std::stringstream ss(line);
    std::string f[5];
    for (std::string& x : f) std::getline(ss, x, ',');
    ASSERT_FALSE(f[4].empty()) << "label column";
    if (f[4] == "move") continue;
    if (!sum.count(f[4])) sum[f[4]].setZero();
    sum[f[4]] += Eigen::Vector3d(std::stod(f[1]), std::stod(f[2]), std::stod(f[3]));
    ++count[f[4]];
  }
  ASSERT_EQ(sum.size(), 6u);
  for (int p = 0; p < 6; ++p) {
    Eigen::Vector3d up = Eigen::Vector3d::Zero();
    up[p / 2] = p % 2 ? -1.0 : 1.0;
    const Eigen::Vector3d mean = sum[labels[p]] / count[labels[p]];
    // 7 counts over ~300 samples and 2048 counts/g: 0.2 mg per mean; the fit
    // has 3 dof left, so the positions agree to a few of those.
    EXPECT_LT((mean - up).cwiseAbs().maxCoeff(), 2e-3) << labels[p];
  }
}

}  // namespace
}  // namespace triadcal

// Tests of run.yaml reading and writing (core/model/run_description.h): defaults,
// every key, the constraint expressions and their units, the column mapping
// and mounting, the exact error text of bad input, and the round trip through
// RunDescriptionToYaml.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "core/model/errors.h"
#include "tests/temp_dir_test.h"
#include "core/model/run_description.h"
#include "core/model/units.h"
#include "core/io/run_description_io.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

class RunDescriptionTest : public testing_fixtures::TempDirTest {
 protected:

  // Writes run.yaml (and an empty run.csv beside it) and returns its path.
  std::string WriteYaml(const std::string& text, const std::string& name = "run.yaml") {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    std::ofstream((dir_ / "run.csv").string()) << "";
    return path;
  }

  // The InputError text of loading `text`, or "" when it loads.
  std::string ErrorOf(const std::string& text) {
    const std::string path = WriteYaml(text);
    try {
      LoadRunDescription(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  std::string Path(const std::string& name = "run.yaml") const { return (dir_ / name).string(); }

};

// Restores an environment variable on scope exit.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) {
      setenv(name, value, 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_.c_str(), old_->c_str(), 1);
    } else {
      unsetenv(name_.c_str());
    }
  }

 private:
  std::string name_;
  std::optional<std::string> old_;
};

TEST_F(RunDescriptionTest, MinimalFileGivesTheDefaults) {
  const RunDescription run = LoadRunDescription(WriteYaml("data: run.csv\n"));
  EXPECT_EQ(run.yaml_path, Path());
  EXPECT_EQ(run.data_path, (dir_ / "run.csv").lexically_normal().string());
  EXPECT_NEAR((run.lever_arm0_m - Eigen::Vector3d(0.138, 0.020, 0.020)).norm(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(run.angle_noise_rad, 15.0 * kArcsecToRad);
  EXPECT_EQ(run.g_mps2, kStandardGravity);
  EXPECT_EQ(run.scale_mV_per_g, Eigen::Vector3d(174, 174, 174));
  EXPECT_EQ(run.bias_mV, Eigen::Vector3d(1500, 1500, 1500));
  EXPECT_EQ(run.noise_mV, 2.0);
  ASSERT_EQ(run.constraints.size(), 1u);
  EXPECT_EQ(run.constraints[0].expr, "dpsi - dlambda2");
  ASSERT_EQ(run.constraints[0].terms.size(), 2u);
  EXPECT_EQ(run.constraints[0].terms[0], std::make_pair(std::string("dpsi"), 1.0));
  EXPECT_EQ(run.constraints[0].terms[1], std::make_pair(std::string("dlambda2"), -1.0));
  EXPECT_EQ(run.constraints[0].value_si, 0.0);
  EXPECT_DOUBLE_EQ(run.constraints[0].sigma_si, 30.0 * kArcsecToRad);
  EXPECT_TRUE(run.columns.empty());
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(run.axis_source[i], i);
    EXPECT_EQ(run.axis_sign[i], 1.0);
  }
}

TEST_F(RunDescriptionTest, ReadsEveryKey) {
  const RunDescription run = LoadRunDescription(WriteYaml(R"(
data: sub/../run.csv
bench:
  lever_arm_mm: [138, -20, 20.5]
  angle_noise_arcsec: 5
  g_mps2: 9.81
triad:
  scale_mV_per_g: [171.5, 175.8, 174.8]
  bias_mV: [1504.2, 1500, -3]
  noise_mV: 0.5
constraints:
  - {expr: "2*dpsi - 0.5 * dlambda2", value_arcmin: 1.5, sigma_arcsec: 30}
  - {expr: "dx2", value: 2, sigma: 0.5}
  - {expr: "dy2 + dz2", sigma_m: 0.001}
  - {expr: "angle_latency.tau", value: 2, sigma: 0.5}
  - {expr: "alpha_x - gamma_y", value_deg: 1, sigma_rad: 0.01}
columns:
  t: {source: time, unit: ms}
  lambda1: {var: enc, unit: rad, scale: -1, offset: 12.5}
  lambda2: {value: 0}
  wx: acc_x
  temp_C: T
mounting: {axes: ["+y", "-z", "-x"]}
)"));
  EXPECT_EQ(run.data_path, (dir_ / "run.csv").lexically_normal().string());
  EXPECT_DOUBLE_EQ(run.lever_arm0_m.x(), 0.138);
  EXPECT_DOUBLE_EQ(run.lever_arm0_m.y(), -0.020);
  EXPECT_DOUBLE_EQ(run.lever_arm0_m.z(), 0.0205);
  EXPECT_DOUBLE_EQ(run.angle_noise_rad, 5.0 * kArcsecToRad);
  EXPECT_EQ(run.g_mps2, 9.81);
  EXPECT_EQ(run.scale_mV_per_g, Eigen::Vector3d(171.5, 175.8, 174.8));
  EXPECT_EQ(run.bias_mV, Eigen::Vector3d(1504.2, 1500, -3));
  EXPECT_EQ(run.noise_mV, 0.5);

  ASSERT_EQ(run.constraints.size(), 5u);
  const Constraint& c0 = run.constraints[0];
  EXPECT_EQ(c0.expr, "2*dpsi - 0.5 * dlambda2");
  ASSERT_EQ(c0.terms.size(), 2u);
  EXPECT_EQ(c0.terms[0], std::make_pair(std::string("dpsi"), 2.0));
  EXPECT_EQ(c0.terms[1], std::make_pair(std::string("dlambda2"), -0.5));
  EXPECT_DOUBLE_EQ(c0.value_si, 1.5 * kArcminToRad);
  EXPECT_DOUBLE_EQ(c0.sigma_si, 30.0 * kArcsecToRad);
  // No suffix: the parameters' own file unit (mm, ms).
  EXPECT_DOUBLE_EQ(run.constraints[1].value_si, 2e-3);
  EXPECT_DOUBLE_EQ(run.constraints[1].sigma_si, 0.5e-3);
  EXPECT_EQ(run.constraints[2].value_si, 0.0);
  EXPECT_DOUBLE_EQ(run.constraints[2].sigma_si, 1e-3);
  EXPECT_EQ(run.constraints[3].terms[0].first, "angle_latency.tau");
  EXPECT_DOUBLE_EQ(run.constraints[3].value_si, 2e-3);
  EXPECT_DOUBLE_EQ(run.constraints[4].value_si, kDegToRad);
  EXPECT_DOUBLE_EQ(run.constraints[4].sigma_si, 0.01);

  ASSERT_EQ(run.columns.size(), 5u);
  EXPECT_EQ(run.columns.at("t").source, "time");
  EXPECT_EQ(run.columns.at("t").unit, "ms");
  const ColumnSource& l1 = run.columns.at("lambda1");
  EXPECT_EQ(l1.source, "enc");
  EXPECT_EQ(l1.unit, "rad");
  EXPECT_EQ(l1.scale, -1.0);
  EXPECT_EQ(l1.offset, 12.5);
  EXPECT_FALSE(l1.constant.has_value());
  EXPECT_EQ(run.columns.at("lambda2").constant, 0.0);
  EXPECT_EQ(run.columns.at("lambda2").source, "");
  EXPECT_EQ(run.columns.at("wx").source, "acc_x");
  EXPECT_EQ(run.columns.at("wx").unit, "mV");
  EXPECT_EQ(run.columns.at("temp_C").source, "T");

  EXPECT_EQ(run.axis_source[0], 1);
  EXPECT_EQ(run.axis_source[1], 2);
  EXPECT_EQ(run.axis_source[2], 0);
  EXPECT_EQ(run.axis_sign[0], 1.0);
  EXPECT_EQ(run.axis_sign[1], -1.0);
  EXPECT_EQ(run.axis_sign[2], -1.0);
}

TEST_F(RunDescriptionTest, EmptyConstraintListMeansNone) {
  const RunDescription run = LoadRunDescription(WriteYaml("data: run.csv\nconstraints: []\n"));
  EXPECT_TRUE(run.constraints.empty());
}

TEST_F(RunDescriptionTest, ReadingsInGDefaultToAThousandMillivoltsPerG) {
  const RunDescription run = LoadRunDescription(
      WriteYaml("data: run.csv\ncolumns: {wx: {source: a, unit: g}, wy: {source: b, unit: g},\n"
                "          wz: {source: c, unit: mg}}\n"));
  EXPECT_EQ(run.scale_mV_per_g, Eigen::Vector3d(1000, 1000, 1000));
  EXPECT_EQ(run.bias_mV, Eigen::Vector3d(0, 0, 0));
}

// The README's template with `unit: g` and its 174 mV/g left in: the
// nominal gain is not the readings' (1000 mV/g for g): one line naming it.
TEST_F(RunDescriptionTest, NominalScaleOfAnotherUnitIsRefused) {
  const std::string yaml =
      WriteYaml("data: run.csv\ncolumns: {wx: {source: a, unit: g}, wy: {source: b, unit: g},\n"
                "          wz: {source: c, unit: g}}\n"
                "triad: {scale_mV_per_g: [174, 174, 174], bias_mV: [0, 0, 0]}\n");
  try {
    LoadRunDescription(yaml);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              yaml + ": triad.scale_mV_per_g[0]: 174 declared for readings in g, which are taken "
                     "at 1000 per g; remove scale_mV_per_g or give the readings' own gain (within "
                     "a factor 2 of it)");
  }
  // The readings' own gain within a factor 2 is a nominal value, not a slip.
  const RunDescription run = LoadRunDescription(
      WriteYaml("data: run.csv\ncolumns: {wx: {source: a, unit: g}, wy: {source: b, unit: g},\n"
                "          wz: {source: c, unit: g}}\ntriad: {scale_mV_per_g: [1010, 990, 1000]}\n"));
  EXPECT_EQ(run.scale_mV_per_g, Eigen::Vector3d(1010, 990, 1000));
}

TEST_F(RunDescriptionTest, ScenarioSectionWithoutData) {
  const YAML::Node node = YAML::Load("{triad: {noise_mV: 3}}");
  const RunDescription run = ParseRunDescription(node, Path("scen.yaml"), "scen.yaml: run");
  EXPECT_TRUE(run.data_path.empty());
  EXPECT_EQ(run.noise_mV, 3.0);
  EXPECT_EQ(run.constraints.size(), 1u);
  try {
    ParseRunDescription(YAML::Load("{triad: {noise_mV: -1}}"), Path("scen.yaml"), "scen.yaml: run");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "scen.yaml: run: triad.noise_mV: must be > 0, got -1");
  }
}

TEST_F(RunDescriptionTest, NominalThetaAndModelConfig) {
  RunDescription run = LoadRunDescription(
      WriteYaml("data: run.csv\nbench: {lever_arm_mm: [100, 0, -5], g_mps2: 9.8}\n"
                "triad: {scale_mV_per_g: [171, 172, 173], bias_mV: [1, 2, 3]}\n"));
  const ParameterLayout layout({Effect::kAngleLatency});
  const Eigen::VectorXd theta = NominalTheta(run, layout);
  ASSERT_EQ(theta.size(), layout.size());
  EXPECT_EQ(theta[kKx], 171.0);
  EXPECT_EQ(theta[kKz], 173.0);
  EXPECT_EQ(theta[kW0x], 1.0);
  EXPECT_EQ(theta[kW0z], 3.0);
  EXPECT_TRUE(theta.segment(kW0z + 1, layout.size() - kW0z - 1).isZero());
  const ModelConfig cfg = MakeModelConfig(run, layout);
  EXPECT_DOUBLE_EQ(cfg.lever_arm0_m.x(), 0.1);
  EXPECT_DOUBLE_EQ(cfg.lever_arm0_m.z(), -0.005);
  EXPECT_EQ(cfg.g_mps2, 9.8);
  EXPECT_TRUE(cfg.layout.has(Effect::kAngleLatency));
}

TEST_F(RunDescriptionTest, ErrorsNameTheKey) {
  const std::string f = Path();
  EXPECT_EQ(ErrorOf("data: run.csv\ntrid: {}\n"),
            f + ": trid: unknown key (allowed: data, bench, triad, gyro, constraints, columns, "
                "mounting, priors, data_format, positions, sensor, time_range_s, temperature_C)");
  EXPECT_EQ(ErrorOf("data: run.csv\ntemperature_C: 400\n"),
            f + ": temperature_C: expected a temperature of -100 to 200 degC, got 400");
  EXPECT_EQ(ErrorOf("data: run.csv\ntriad: {scale_mV_per_g: [174, 174]}\n"),
            f + ": triad.scale_mV_per_g: expected a list of 3 numbers, got 2");
  EXPECT_EQ(ErrorOf("data: run.csv\ntriad: {scale_mV_per_g: [174, x, 174]}\n"),
            f + ": triad.scale_mV_per_g[1]: expected a number, got 'x'");
  EXPECT_EQ(ErrorOf("data: run.csv\ntriad: {scale_mV_per_g: [174, -174, 174]}\n"),
            f + ": triad.scale_mV_per_g[1]: must be > 0, got -174 (an inverted axis belongs in "
                "mounting.axes)");
  EXPECT_EQ(ErrorOf("data: run.csv\nbench: {lever_arm: [1, 2, 3]}\n"),
            f + ": bench.lever_arm: unknown key (allowed: lever_arm_mm, angle_noise_arcsec, "
                "g_mps2, latitude_deg, heading_deg)");
  EXPECT_EQ(ErrorOf("data: run.csv\ntriad: {noise_mV: 1}\ntriad: {noise_mV: 2}\n"),
            f + ": triad: given twice");
  EXPECT_EQ(ErrorOf("data: run.csv\ntriad: {noise_mV: 1, noise_mV: 2}\n"),
            f + ": triad.noise_mV: given twice");
  EXPECT_EQ(ErrorOf("bench: {}\n"),
            f + ": data: missing: the data file (relative to this file, or shared:PATH)");
  EXPECT_EQ(ErrorOf("- data\n"), f + ": expected a map of keys (data, bench, triad, ...)");
  EXPECT_EQ(ErrorOf("data: run.csv\nmounting: {axes: [\"+y\", \"-y\", \"+x\"]}\n"),
            f + ": mounting.axes: IMU axis y used twice: the axes must be a signed "
                "permutation of x, y, z");
  EXPECT_EQ(ErrorOf("data: run.csv\nmounting: {axes: [\"+y\", \"+w\", \"+x\"]}\n"),
            f + ": mounting.axes[1]: expected +x, -x, +y, -y, +z or -z, got '+w'");
  EXPECT_EQ(ErrorOf("data: run.csv\nmounting: {axes: [\"+y\", \"+x\"]}\n"),
            f + ": mounting.axes: expected a list of 3 signed IMU axes like [\"+y\", \"-z\", "
                "\"-x\"], got 2 entries");
  EXPECT_EQ(ErrorOf("data: run.csv\ncolumns: {wx: {source: a, unit: volts}}\n"),
            f + ": columns.wx.unit: unknown unit 'volts' for wx (allowed: mV, V, g, mg, m/s^2, "
                "m/s\xC2\xB2, counts)");
  EXPECT_EQ(ErrorOf("data: run.csv\ncolumns: {w_x: a}\n"),
            f + ": columns.w_x: unknown key (allowed: t, lambda1, lambda2, wx, wy, wz, "
                "lambda1_rate, lambda2_rate, temp_C, gx, gy, gz, label)");
  EXPECT_EQ(ErrorOf("data: run.csv\ncolumns: {lambda2: {source: a, value: 0}}\n"),
            f + ": columns.lambda2: give exactly one of source, var or value");
  EXPECT_EQ(ErrorOf("data: run.csv\ncolumns: {lambda2: 0}\n"),
            f + ": columns.lambda2: got the number 0; write {value: 0} for a constant "
                "channel, or quote a column named \"0\"");
}

TEST_F(RunDescriptionTest, ConstraintErrors) {
  const std::string f = Path();
  auto with = [](const std::string& c) { return "data: run.csv\nconstraints:\n  - " + c + "\n"; };
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsii - dlambda2\", sigma_arcsec: 30}")),
            f + ": constraints[0].expr: unknown parameter 'dpsii' in \"dpsii - dlambda2\" "
                "(known: Kx Ky Kz W0x W0y W0z alpha_x alpha_y beta_x beta_z gamma_y gamma_z "
                "Kxx Kxy Kxz Kyx Kyy Kyz Kzx Kzy Kzz dpsi dtheta_c dlambda2 dx2 dy2 dz2, and "
                "effect.param names, see `triadcal params`)");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi - dlambda2\", sigma_arcsec: 0}")),
            f + ": constraints[0].sigma_arcsec: must be > 0, got 0");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi - dlambda2\", sigma: -2}")),
            f + ": constraints[0].sigma: must be > 0, got -2");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi - dlambda2\", value_arcmin: 0}")),
            f + ": constraints[0]: missing sigma (e.g. sigma_arcsec: 30)");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi dlambda2\", sigma_arcsec: 30}")),
            f + ": constraints[0].expr: expected '+' or '-' at position 6 of \"dpsi "
                "dlambda2\"");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi - 3\", sigma_arcsec: 30}")),
            f + ": constraints[0].expr: constant term '3' in \"dpsi - 3\" (put constants in "
                "value_...)");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi - dpsi\", sigma_arcsec: 30}")),
            f + ": constraints[0].expr: all coefficients are zero in \"dpsi - dpsi\"");
  EXPECT_EQ(ErrorOf(with("{expr: \"dx2\", value_arcmin: 1, sigma_mm: 1}")),
            f + ": constraints[0].value_arcmin: an angle unit, but dx2 is in mm");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi + dx2\", sigma: 1}")),
            f + ": constraints[0].sigma: parameters of different units (dpsi in arcmin, dx2 in "
                "mm); give the unit as a suffix, e.g. sigma_arcmin");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi\", sigma_furlong: 1}")),
            f + ": constraints[0].sigma_furlong: unknown key (allowed: expr, value, sigma, "
                "value_arcmin, sigma_arcmin, value_arcsec, sigma_arcsec, value_deg, sigma_deg, "
                "value_rad, sigma_rad, value_mm, sigma_mm, value_m, sigma_m)");
  EXPECT_EQ(ErrorOf(with("{expr: \"dpsi\", sigma_arcsec: 1, sigma_arcmin: 1}")),
            f + ": constraints[0]: both 'sigma_arcsec' and 'sigma_arcmin' given; use one");
}

TEST_F(RunDescriptionTest, YamlSyntaxErrorNamesTheLine) {
  const std::string err = ErrorOf("data: run.csv\ntriad:\n  bias_mV: [1, 2\n");
  EXPECT_EQ(err.rfind(Path() + ":4: YAML syntax error: ", 0), 0u) << err;
}

TEST_F(RunDescriptionTest, MissingSharedFolder) {
  ScopedEnv env("TRIADCAL_SHARED", nullptr);
  // The temp folder has no "shared" folder beside any of its parents.
  if (fs::exists(fs::temp_directory_path().parent_path() / "shared") ||
      fs::exists(fs::temp_directory_path() / "shared")) {
    GTEST_SKIP() << "a shared folder exists near the temp folder";
  }
  EXPECT_EQ(ErrorOf("data: shared:data/none.mat\n"),
            Path() +
                ": data: shared data folder not found for 'shared:data/none.mat' (set "
                "TRIADCAL_SHARED)");
}

TEST_F(RunDescriptionTest, SharedPrefixUsesTheEnvironment) {
  ScopedEnv env("TRIADCAL_SHARED", dir_.string().c_str());
  const RunDescription run = LoadRunDescription(WriteYaml("data: shared:data/x.mat\n"));
  EXPECT_EQ(run.data_path, (dir_ / "data/x.mat").string());
}

void ExpectSameDescription(const RunDescription& a, const RunDescription& b) {
  EXPECT_EQ(a.data_path, b.data_path);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(a.lever_arm0_m[i], b.lever_arm0_m[i], 1e-15 * std::abs(a.lever_arm0_m[i]));
    EXPECT_EQ(a.scale_mV_per_g[i], b.scale_mV_per_g[i]);
    EXPECT_EQ(a.bias_mV[i], b.bias_mV[i]);
    EXPECT_EQ(a.axis_source[i], b.axis_source[i]);
    EXPECT_EQ(a.axis_sign[i], b.axis_sign[i]);
  }
  EXPECT_NEAR(a.angle_noise_rad, b.angle_noise_rad, 1e-15 * a.angle_noise_rad);
  EXPECT_EQ(a.g_mps2, b.g_mps2);
  EXPECT_EQ(a.noise_mV, b.noise_mV);
  ASSERT_EQ(a.latitude_rad.has_value(), b.latitude_rad.has_value());
  ASSERT_EQ(a.heading_rad.has_value(), b.heading_rad.has_value());
  if (a.latitude_rad) {
    EXPECT_NEAR(*a.latitude_rad, *b.latitude_rad, 1e-15);
    EXPECT_NEAR(*a.heading_rad, *b.heading_rad, 1e-15);
  }
  ASSERT_EQ(a.gyro.has_value(), b.gyro.has_value());
  if (a.gyro) {
    EXPECT_EQ(a.gyro->scale, b.gyro->scale);
    EXPECT_NEAR((a.gyro->bias_rad_s - b.gyro->bias_rad_s).norm(), 0.0, 1e-15);
    EXPECT_NEAR((a.gyro->noise_rad_s - b.gyro->noise_rad_s).norm(), 0.0, 1e-15);
    EXPECT_EQ(a.gyro->noise_auto, b.gyro->noise_auto);
  }
  ASSERT_EQ(a.constraints.size(), b.constraints.size());
  for (std::size_t j = 0; j < a.constraints.size(); ++j) {
    EXPECT_EQ(a.constraints[j].terms, b.constraints[j].terms);
    EXPECT_NEAR(a.constraints[j].value_si, b.constraints[j].value_si,
                1e-15 * std::abs(a.constraints[j].value_si));
    EXPECT_NEAR(a.constraints[j].sigma_si, b.constraints[j].sigma_si,
                1e-15 * a.constraints[j].sigma_si);
  }
  ASSERT_EQ(a.columns.size(), b.columns.size());
  for (const auto& [name, c] : a.columns) {
    const ColumnSource& d = b.columns.at(name);
    EXPECT_EQ(c.source, d.source) << name;
    EXPECT_EQ(c.constant, d.constant) << name;
    EXPECT_EQ(c.unit, d.unit) << name;
    EXPECT_EQ(c.scale, d.scale) << name;
    EXPECT_EQ(c.offset, d.offset) << name;
    EXPECT_EQ(c.counts_per_g, d.counts_per_g) << name;
    EXPECT_EQ(c.counts_per_dps, d.counts_per_dps) << name;
  }
}

TEST_F(RunDescriptionTest, YamlRoundTrip) {
  const RunDescription run = LoadRunDescription(WriteYaml(R"(
data: run.csv
bench: {lever_arm_mm: [138.1, -20.3, 0.7], angle_noise_arcsec: 15.5, g_mps2: 9.8123}
triad: {scale_mV_per_g: [171.53, 175.8, 174.8], bias_mV: [1504.2, 1499.9, 1500.1],
        noise_mV: 2.25}
constraints:
  - {expr: "2*dpsi - 0.5 * dlambda2", value_arcmin: 1.5, sigma_arcsec: 30}
  - {expr: "dx2 - dy2", value_mm: 0.1, sigma_mm: 2}
  - {expr: "angle_latency.tau", value: 2, sigma: 0.5}
columns:
  t: {source: "time s", unit: ms}
  lambda1: {var: enc, unit: rad, scale: -1, offset: 12.5}
  lambda2: {value: 0.25}
  wx: acc_x
  wy: {source: "0", unit: V}
  temp_C: T
mounting: {axes: ["+y", "-z", "-x"]}
)"));
  const std::string text = RunDescriptionToYaml(run, "run.csv");
  const std::string path2 = WriteYaml(text, "run2.yaml");
  const RunDescription back = LoadRunDescription(path2);
  ExpectSameDescription(run, back);
  // Written again, the text is the same: nothing drifts.
  EXPECT_EQ(RunDescriptionToYaml(back, "run.csv"), text);
}

// sensor: {serial, model}, both optional, kept as text and written back.
TEST_F(RunDescriptionTest, SensorSerialAndModel) {
  const RunDescription run =
      LoadRunDescription(WriteYaml("data: run.csv\nsensor: {serial: 0042, model: ADXL325}\n"));
  EXPECT_EQ(run.sensor_serial, "0042");
  EXPECT_EQ(run.sensor_model, "ADXL325");
  const RunDescription back =
      LoadRunDescription(WriteYaml(RunDescriptionToYaml(run, "run.csv"), "run2.yaml"));
  EXPECT_EQ(back.sensor_serial, "0042");
  EXPECT_EQ(back.sensor_model, "ADXL325");
  const RunDescription model_only =
      LoadRunDescription(WriteYaml("data: run.csv\nsensor: {model: ADXL325}\n"));
  EXPECT_EQ(model_only.sensor_serial, "");
  EXPECT_EQ(RunDescriptionToYaml(model_only, "run.csv").find("serial"), std::string::npos);
  EXPECT_EQ(ErrorOf("data: run.csv\nsensor: {serial_no: 1}\n"),
            Path() + ": sensor.serial_no: unknown key (allowed: serial, model)");
}

TEST_F(RunDescriptionTest, DefaultRoundTripWritesTheSpecKeysOnly) {
  const RunDescription run = LoadRunDescription(WriteYaml("data: run.csv\n"));
  const std::string text = RunDescriptionToYaml(run, "run.csv");
  EXPECT_EQ(text.find("columns"), std::string::npos) << text;
  EXPECT_EQ(text.find("mounting"), std::string::npos) << text;
  EXPECT_EQ(text.find("g_mps2"), std::string::npos) << text;
  EXPECT_NE(text.find("expr: \"dpsi - dlambda2\", value_arcmin: 0, sigma_arcsec: 30"),
            std::string::npos)
      << text;
  ExpectSameDescription(run, LoadRunDescription(WriteYaml(text, "run2.yaml")));

  RunDescription none = run;
  none.constraints.clear();
  const std::string text2 = RunDescriptionToYaml(none, "run.csv");
  EXPECT_NE(text2.find("constraints: []"), std::string::npos) << text2;
  EXPECT_TRUE(LoadRunDescription(WriteYaml(text2, "run3.yaml")).constraints.empty());
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

TEST(RunDescriptionPriors, ParsedValidatedAndRoundTripped) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "triadcal_priors_test";
  fs::create_directories(dir);
  const fs::path yaml = dir / "run.yaml";
  std::ofstream(yaml) << "data: run.csv\npriors: {dx2: 30, angle_latency.tau: 5}\n";
  const RunDescription run = LoadRunDescription(yaml.string());
  EXPECT_EQ(run.prior_sigma.at("dx2"), 30.0);
  EXPECT_EQ(run.prior_sigma.at("angle_latency.tau"), 5.0);
  std::ofstream(yaml) << RunDescriptionToYaml(run, "run.csv");
  EXPECT_EQ(LoadRunDescription(yaml.string()).prior_sigma, run.prior_sigma);

  std::ofstream(yaml) << "data: run.csv\npriors: {dx9: 30}\n";
  try {
    LoadRunDescription(yaml.string());
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              yaml.string() + ": priors.dx9: unknown parameter (see `triadcal params`)");
  }
  std::ofstream(yaml) << "data: run.csv\npriors: {dx2: 0}\n";
  EXPECT_THROW(LoadRunDescription(yaml.string()), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// triad.noise_mV: one figure, one per channel, or auto; round-tripped.
TEST_F(RunDescriptionTest, NoiseIsOneFigurePerChannelOrAuto) {
  const std::string head = "data: run.csv\ntriad: {noise_mV: ";
  RunDescription r = LoadRunDescription(WriteYaml(head + "[1, 2, 3]}\n"));
  ASSERT_TRUE(r.noise_channel_mV.has_value());
  EXPECT_EQ(r.ChannelNoise_mV(), Eigen::Vector3d(1, 2, 3));
  EXPECT_FALSE(r.noise_auto);
  EXPECT_NE(RunDescriptionToYaml(r, "run.csv").find("noise_mV: [1, 2, 3]"), std::string::npos)
      << RunDescriptionToYaml(r, "run.csv");
  r = LoadRunDescription(WriteYaml(head + "auto}\n"));
  EXPECT_TRUE(r.noise_auto);
  EXPECT_NE(RunDescriptionToYaml(r, "run.csv").find("noise_mV: auto"), std::string::npos);
  r = LoadRunDescription(WriteYaml(head + "1.5}\n"));
  EXPECT_EQ(r.ChannelNoise_mV(), Eigen::Vector3d::Constant(1.5));
  const std::string f = Path();
  EXPECT_EQ(ErrorOf(head + "[1, -2, 3]}\n"), f + ": triad.noise_mV[1]: must be > 0, got -2");
  EXPECT_EQ(ErrorOf(head + "abc}\n"), f + ": triad.noise_mV: expected a number, got 'abc'");
  EXPECT_EQ(ErrorOf(head + "[1, 2]}\n"),
            f + ": triad.noise_mV: expected a list of 3 numbers, got 2");
}

}  // namespace
}  // namespace triadcal

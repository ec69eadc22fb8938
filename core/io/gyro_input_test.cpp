// The gyro triad on input (SPEC section 10): run.yaml's gyro block and the
// bench's latitude and heading, read and written back; the gyro columns gx gy
// gz with their units, mapping and mounting; and every bad input with the
// exact error (or warning) it must give, including a gyro unit that the
// bench's own angle rate shows to be wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/io/file_util.h"
#include "core/io/run_description_io.h"
#include "core/io/run_io.h"
#include "core/model/errors.h"
#include "core/model/units.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

// A bench run of 10 s at 100 Hz: lambda1 = 90 sin(2 pi t / 6), lambda2 =
// 30 sin(2 pi t / 4) [deg], the readings following gravity, and a gyro reading
// the input rate of frame 2 (0, lambda1', 0) turned by lambda2, plus
// (lambda2', 0, 0) and a small bias [deg/s], times gyro_factor (kDegToRad:
// the same rates written in rad/s).
struct GyroRun {
  std::vector<double> t, l1, l2, w[3], g[3];  // deg, mV, deg/s (as written)
};

GyroRun MakeGyroRun(double gyro_factor, bool still = false) {
  GyroRun r;
  const double a1 = still ? 0.0 : 90.0, a2 = still ? 0.0 : 30.0;
  for (int k = 0; k < 1000; ++k) {
    const double t = 0.01 * k;
    const double w1 = 2.0 * kPi / 6.0, w2 = 2.0 * kPi / 4.0;
    const double l1 = a1 * std::sin(w1 * t) + 5.0, l2 = a2 * std::sin(w2 * t);
    const double r1 = a1 * w1 * std::cos(w1 * t), r2 = a2 * w2 * std::cos(w2 * t);  // deg/s
    const double c = std::cos(l2 * kDegToRad), s = std::sin(l2 * kDegToRad);
    r.t.push_back(t);
    r.l1.push_back(l1);
    r.l2.push_back(l2);
    r.w[0].push_back(1500.0 + 174.0 * std::sin(l1 * kDegToRad) + 0.01 * (k % 7));
    r.w[1].push_back(1500.0 + 174.0 * std::cos(l1 * kDegToRad) * s);
    r.w[2].push_back(1500.0 + 174.0 * std::cos(l1 * kDegToRad) * c);
    const double g[3] = {r2 + 0.5, c * r1 - 0.25, -s * r1 + 0.125};
    for (int i = 0; i < 3; ++i) r.g[i].push_back(g[i] * gyro_factor);
  }
  return r;
}

// CSV text of the run with the given gyro column names ("" leaves one out);
// row k is on file line k + 2.
std::string GyroCsv(const GyroRun& r,
                    const std::vector<std::string>& gyro_names = {"gx", "gy", "gz"}) {
  std::string text = "t,lambda1,lambda2,wx,wy,wz";
  for (const std::string& n : gyro_names) {
    if (!n.empty()) text += "," + n;
  }
  text += "\n";
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    text += FormatDouble(r.t[k]) + "," + FormatDouble(r.l1[k]) + "," + FormatDouble(r.l2[k]);
    for (int i = 0; i < 3; ++i) text += "," + FormatDouble(r.w[i][k]);
    for (std::size_t i = 0; i < gyro_names.size(); ++i) {
      if (!gyro_names[i].empty()) text += "," + FormatDouble(r.g[i][k]);
    }
    text += "\n";
  }
  return text;
}

class GyroInputTest : public testing_fixtures::TempDirTest {
 protected:
  RunDescription Describe(const std::string& yaml) const {
    return LoadRunDescription(WriteText("run.yaml", yaml));
  }
  // The InputError of reading run.yaml, or "".
  std::string YamlError(const std::string& yaml) const {
    try {
      Describe(yaml);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
  // The InputError of loading the data of run.yaml, or "".
  std::string DataError(const std::string& yaml) const {
    try {
      RunWarnings w;
      LoadRunData(Describe(yaml), &w);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

constexpr const char* kGyroYaml = "data: run.csv\ngyro: {scale: [1, 1, 1]}\n";

TEST_F(GyroInputTest, RunYamlReadsTheGyroBlockAndTheBenchLocation) {
  const RunDescription run = Describe(
      "data: run.csv\n"
      "bench: {latitude_deg: 48.15, heading_deg: -12.5}\n"
      "gyro: {scale: [1.01, -0.99, 1], bias_dps: [0.5, -0.2, 0.1], noise_dps: 0.02}\n");
  ASSERT_TRUE(run.gyro.has_value());
  EXPECT_EQ(run.gyro->scale, Eigen::Vector3d(1.01, -0.99, 1));
  EXPECT_NEAR((run.gyro->bias_rad_s - Eigen::Vector3d(0.5, -0.2, 0.1) * kDegToRad).norm(), 0.0,
              1e-18);
  EXPECT_EQ(run.gyro->noise_rad_s, Eigen::Vector3d::Constant(0.02 * kDegToRad));
  EXPECT_FALSE(run.gyro->noise_auto);
  ASSERT_TRUE(run.latitude_rad && run.heading_rad);
  EXPECT_DOUBLE_EQ(*run.latitude_rad, 48.15 * kDegToRad);
  EXPECT_DOUBLE_EQ(*run.heading_rad, -12.5 * kDegToRad);

  // Written back and read again: the same, and the same text again.
  const std::string text = RunDescriptionToYaml(run, "run.csv");
  EXPECT_NE(text.find("latitude_deg: 48.15"), std::string::npos) << text;
  EXPECT_NE(text.find("heading_deg: -12.5"), std::string::npos) << text;
  EXPECT_NE(text.find("gyro:\n  scale: [1.01, -0.99, 1]\n  bias_dps: [0.5, -0.2, 0.1]\n"
                      "  noise_dps: 0.02\n"),
            std::string::npos)
      << text;
  const RunDescription back = Describe(text);
  ASSERT_TRUE(back.gyro.has_value());
  EXPECT_EQ(back.gyro->scale, run.gyro->scale);
  EXPECT_NEAR((back.gyro->bias_rad_s - run.gyro->bias_rad_s).norm(), 0.0, 1e-18);
  EXPECT_NEAR((back.gyro->noise_rad_s - run.gyro->noise_rad_s).norm(), 0.0, 1e-18);
  EXPECT_NEAR(*back.latitude_rad, *run.latitude_rad, 1e-15);
  EXPECT_NEAR(*back.heading_rad, *run.heading_rad, 1e-15);
  EXPECT_EQ(RunDescriptionToYaml(back, "run.csv"), text);

  // Noise per channel and auto, also written back.
  const RunDescription per = Describe("data: run.csv\ngyro: {noise_dps: [0.01, 0.02, 0.03]}\n");
  EXPECT_NEAR((per.gyro->noise_rad_s - Eigen::Vector3d(0.01, 0.02, 0.03) * kDegToRad).norm(), 0,
              1e-18);
  EXPECT_NE(RunDescriptionToYaml(per, "run.csv").find("noise_dps: [0.01, 0.02, 0.03]"),
            std::string::npos);
  const RunDescription aut = Describe("data: run.csv\ngyro: {noise_dps: auto}\n");
  EXPECT_TRUE(aut.gyro->noise_auto);
  EXPECT_NE(RunDescriptionToYaml(aut, "run.csv").find("noise_dps: auto"), std::string::npos);

  // The defaults of an empty block; none of it without one.
  const RunDescription empty = Describe("data: run.csv\ngyro: {}\n");
  ASSERT_TRUE(empty.gyro.has_value());
  EXPECT_EQ(empty.gyro->scale, Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(empty.gyro->bias_rad_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(empty.gyro->noise_rad_s, Eigen::Vector3d::Constant(0.05 * kDegToRad));
  const RunDescription plain = Describe("data: run.csv\n");
  EXPECT_FALSE(plain.gyro.has_value());
  EXPECT_FALSE(plain.latitude_rad.has_value());
  const std::string plain_text = RunDescriptionToYaml(plain, "run.csv");
  EXPECT_EQ(plain_text.find("gyro"), std::string::npos) << plain_text;
  EXPECT_EQ(plain_text.find("latitude"), std::string::npos) << plain_text;

  // Priors on gyro parameters: with a gyro block.
  const RunDescription prior = Describe("data: run.csv\ngyro: {}\npriors: {gyro.W0x: 2}\n");
  EXPECT_EQ(prior.prior_sigma.at("gyro.W0x"), 2.0);
}

TEST_F(GyroInputTest, RunYamlErrorsNameTheKey) {
  const std::string f = Path("run.yaml");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"gyro: {scales: [1, 1, 1]}",
       "gyro.scales: unknown key (allowed: scale, bias_dps, noise_dps)"},
      {"gyro: [1, 1, 1]", "gyro: expected a map, got a list"},
      {"gyro: {scale: [1, 0, 1]}", "gyro.scale[1]: must not be 0 (readings per deg/s; nominal 1)"},
      {"gyro: {scale: [1, 1]}", "gyro.scale: expected a list of 3 numbers, got 2"},
      {"gyro: {bias_dps: 0.5}", "gyro.bias_dps: expected a list of 3 numbers, got '0.5'"},
      {"gyro: {noise_dps: 0}", "gyro.noise_dps: must be > 0, got 0"},
      {"gyro: {noise_dps: -0.1}", "gyro.noise_dps: must be > 0, got -0.1"},
      {"gyro: {noise_dps: [0.1, -0.1, 0.1]}", "gyro.noise_dps[1]: must be > 0, got -0.1"},
      {"gyro: {noise_dps: fast}", "gyro.noise_dps: expected a number, got 'fast'"},
      {"bench: {latitude_deg: 48}",
       "bench.latitude_deg: given without bench.heading_deg (Earth's rate needs both; give "
       "both, or neither)"},
      {"bench: {heading_deg: 10}",
       "bench.heading_deg: given without bench.latitude_deg (Earth's rate needs both; give "
       "both, or neither)"},
      {"bench: {latitude_deg: 95, heading_deg: 0}",
       "bench.latitude_deg: must be within [-90, 90] deg, got 95"},
      {"bench: {latitude_deg: 45, heading_deg: north}",
       "bench.heading_deg: expected a number, got 'north'"},
      {"priors: {gyro.W0x: 1}",
       "priors.gyro.W0x: a gyro parameter, but this run has no gyro block"},
      {"gyro: {}\npriors: {gyro.W0q: 1}",
       "priors.gyro.W0q: unknown parameter (see `triadcal params`)"},
      {"columns: {gx: {source: a, unit: counts}}",
       "columns.gx: gyro readings in counts need their count scale: counts_per_dps (e.g. 131)"},
      {"columns: {gy: {source: a, unit: counts, counts_per_g: 131}}",
       "columns.gy.counts_per_g: unknown key (allowed: source, var, unit, scale, offset, value, "
       "counts_per_dps)"},
      {"columns: {gz: {source: a, unit: deg/s, counts_per_dps: 131}}",
       "columns.gz.counts_per_dps: only with unit: counts"},
      {"columns: {gx: {source: a, unit: dps}}",
       "columns.gx.unit: unknown unit 'dps' for gx (allowed: deg/s, rad/s, counts)"},
      {"columns: {wx: {source: a, unit: counts, counts_per_dps: 1}}",
       "columns.wx.counts_per_dps: unknown key (allowed: source, var, unit, scale, offset, value, "
       "counts_per_g)"},
  };
  for (const auto& [yaml, message] : cases) {
    EXPECT_EQ(YamlError("data: run.csv\n" + yaml + "\n"), f + ": " + message) << yaml;
  }
}

TEST_F(GyroInputTest, ColumnsAreReadInRadiansPerSecondOnThePlatformAxes) {
  const GyroRun r = MakeGyroRun(1.0);
  WriteText("run.csv", GyroCsv(r));
  RunWarnings w;
  const RunData plain = LoadRunData(Describe(kGyroYaml), &w);
  EXPECT_TRUE(w.lines.empty()) << w.lines.front();
  ASSERT_TRUE(plain.has_gyro());
  ASSERT_EQ(plain.gyro_rad_s[0].size(), r.t.size());
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    for (int i = 0; i < 3; ++i) ASSERT_EQ(plain.gyro_rad_s[i][k], r.g[i][k] * kDegToRad) << k;
  }

  // The mounting turns the gyro's axes as the accelerometer's.
  const RunData mounted = LoadRunData(
      Describe(std::string(kGyroYaml) + "mounting: {axes: [\"+y\", \"-z\", \"-x\"]}\n"), &w);
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    ASSERT_EQ(mounted.gyro_rad_s[0][k], r.g[1][k] * kDegToRad) << k;
    ASSERT_EQ(mounted.gyro_rad_s[1][k], -r.g[2][k] * kDegToRad) << k;
    ASSERT_EQ(mounted.gyro_rad_s[2][k], -r.g[0][k] * kDegToRad) << k;
    ASSERT_EQ(mounted.w_mV[0][k], r.w[1][k]) << k;
    ASSERT_EQ(mounted.w_mV[2][k], -r.w[0][k]) << k;
  }

  // Mapped columns: rad/s, counts at counts_per_dps, and a scale.
  GyroRun m = r;
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    m.g[0][k] = r.g[0][k] * kDegToRad;
    m.g[1][k] = std::round(r.g[1][k] * 131.0);
    m.g[2][k] = -r.g[2][k];
  }
  WriteText("mapped.csv", GyroCsv(m, {"rx", "ry", "rz"}));
  const RunData mapped =
      LoadRunData(Describe("data: mapped.csv\ngyro: {}\ncolumns:\n  gx: {source: rx, unit: rad/s}\n"
                           "  gy: {source: ry, unit: counts, counts_per_dps: 131}\n"
                           "  gz: {source: rz, scale: -1}\n"),
                  &w);
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    ASSERT_NEAR(mapped.gyro_rad_s[0][k], r.g[0][k] * kDegToRad, 1e-15) << k;
    ASSERT_NEAR(mapped.gyro_rad_s[1][k], m.g[1][k] / 131.0 * kDegToRad, 1e-15) << k;
    ASSERT_NEAR(mapped.gyro_rad_s[2][k], r.g[2][k] * kDegToRad, 1e-15) << k;
  }
}

TEST_F(GyroInputTest, ColumnsWithoutAGyroBlockAreIgnoredWithAWarning) {
  const GyroRun r = MakeGyroRun(1.0);
  WriteText("run.csv", GyroCsv(r));
  RunWarnings w;
  const RunData data = LoadRunData(Describe("data: run.csv\n"), &w);
  ASSERT_EQ(w.lines.size(), 1u);
  EXPECT_EQ(w.lines[0],
            "gx gy gz present but run.yaml has no gyro block: the gyro is not "
            "calibrated");
  EXPECT_FALSE(data.has_gyro());
  EXPECT_EQ(data.size(), r.t.size());
  // A column named gx alone is just another column.
  WriteText("run.csv", GyroCsv(r, {"gx", "", ""}));
  RunWarnings w2;
  EXPECT_FALSE(LoadRunData(Describe("data: run.csv\n"), &w2).has_gyro());
  EXPECT_TRUE(w2.lines.empty()) << w2.lines.front();
}

TEST_F(GyroInputTest, AGyroBlockNeedsAllThreeColumns) {
  const GyroRun r = MakeGyroRun(1.0);
  const std::string csv = Path("run.csv");
  const std::string why =
      " (run.yaml has a gyro block: give gx, gy and gz, or remove the block; header: ";
  WriteText("run.csv", GyroCsv(r, {}));
  EXPECT_EQ(DataError(kGyroYaml), csv + ":1: missing gyro columns 'gx', 'gy', 'gz'" + why +
                                      "t, lambda1, lambda2, wx, wy, wz)");
  WriteText("run.csv", GyroCsv(r, {"gx", "gy", ""}));
  EXPECT_EQ(DataError(kGyroYaml), csv + ":1: missing gyro column 'gz'" + why +
                                      "t, lambda1, lambda2, wx, wy, wz, gx, gy)");
  EXPECT_EQ(DataError(std::string(kGyroYaml) + "columns: {gx: rate_x}\n"),
            csv + ":1: missing gyro columns 'rate_x' (gx), 'gz'" + why +
                "t, lambda1, lambda2, wx, wy, wz, gx, gy)");
}

TEST_F(GyroInputTest, NonFiniteReadingNamesTheLine) {
  GyroRun r = MakeGyroRun(1.0);
  r.g[0][5] = std::nan("");
  WriteText("run.csv", GyroCsv(r));
  const std::string csv = Path("run.csv");
  EXPECT_EQ(DataError(kGyroYaml), csv + ":7: column 'gx': NaN (every sample must be a number)");
  r.g[0][5] = 1.0;
  r.g[2][3] = -INFINITY;
  WriteText("run.csv", GyroCsv(r));
  EXPECT_EQ(DataError(kGyroYaml),
            csv + ":5: column 'gz': infinite value (every sample must be a number)");
  // Without a gyro block the columns are not read: no error.
  RunWarnings w;
  EXPECT_EQ(LoadRunData(Describe("data: run.csv\n"), &w).size(), r.t.size());
}

// Whether `text` starts with `head` and ends with `tail`.
::testing::AssertionResult StartsAndEnds(const std::string& text, const std::string& head,
                                         const std::string& tail) {
  if (text.rfind(head, 0) == 0 && text.size() >= tail.size() &&
      text.compare(text.size() - tail.size(), tail.size(), tail) == 0) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure() << "'" << text << "'";
}

// The ratio a gyro unit message gives: "..., R times the bench's angle rate".
double RatioIn(const std::string& message) {
  const std::string head = " deg/s as declared, ", tail = " times the bench's angle rate (RMS ";
  const std::size_t a = message.find(head), b = message.find(tail);
  if (a == std::string::npos || b == std::string::npos || b < a) return -1.0;
  return std::stod(message.substr(a + head.size(), b - a - head.size()));
}

TEST_F(GyroInputTest, UnitIsJudgedByTheBenchsAngleRate) {
  const std::string csv = Path("run.csv");
  const std::string labels = csv + ": column 'gx', column 'gy', column 'gz': ";
  // rad/s read as the default deg/s: 57 times less than the bench's rate.
  WriteText("run.csv", GyroCsv(MakeGyroRun(kDegToRad)));
  const std::string rad = DataError(kGyroYaml);
  EXPECT_TRUE(StartsAndEnds(rad, labels + "the RMS of |g| over the run is ",
                            ": the gyro readings look like rad/s, not deg/s; declare `unit: "
                            "rad/s` (columns.gx, gy, gz)"));
  EXPECT_NEAR(RatioIn(rad), kDegToRad, 0.01 * kDegToRad) << rad;
  // Declared so, it loads.
  const std::string as_rad =
      "columns: {gx: {source: gx, unit: rad/s}, gy: {source: gy, unit: rad/s}, "
      "gz: {source: gz, unit: rad/s}}\n";
  RunWarnings w;
  EXPECT_TRUE(LoadRunData(Describe(kGyroYaml + as_rad), &w).has_gyro());

  // deg/s declared as rad/s: 57 times more.
  WriteText("run.csv", GyroCsv(MakeGyroRun(1.0)));
  EXPECT_TRUE(StartsAndEnds(DataError(kGyroYaml + as_rad), labels,
                            ": the gyro readings look like deg/s declared as rad/s; declare "
                            "`unit: deg/s` (columns.gx, gy, gz)"));
  // Counts read as deg/s: beyond a factor 5 of the nominal scale.
  WriteText("run.csv", GyroCsv(MakeGyroRun(131.0)));
  const std::string counts = DataError(kGyroYaml);
  EXPECT_TRUE(StartsAndEnds(counts, labels,
                            " (bound: within a factor 5): check the gyro's unit (columns.gx, gy, "
                            "gz: deg/s, rad/s or counts with counts_per_dps) and gyro.scale"));
  EXPECT_NEAR(RatioIn(counts), 131.0, 1.3) << counts;
  // ... unless the nominal scale says the readings are that large.
  EXPECT_TRUE(
      LoadRunData(Describe("data: run.csv\ngyro: {scale: [131, 131, 131]}\n"), &w).has_gyro());
  // A bench that does not move gives nothing to judge by.
  WriteText("run.csv", GyroCsv(MakeGyroRun(kDegToRad, /*still=*/true)));
  EXPECT_EQ(DataError("data: run.csv\ngyro: {}\ncolumns: {lambda1: {value: 5}, lambda2: "
                      "{value: 0}}\n"),
            "");
}

TEST_F(GyroInputTest, SortingDuplicatesAndTimeRangeCarryTheGyro) {
  GyroRun r = MakeGyroRun(1.0);
  // Rows 10 and 11 swapped (sort_by_time puts them back), and row 21 a
  // repeat of row 20's time stamp with other readings (dropped).
  GyroRun s = r;
  for (auto* v : {&s.t, &s.l1, &s.l2, &s.w[0], &s.w[1], &s.w[2], &s.g[0], &s.g[1], &s.g[2]}) {
    std::swap((*v)[10], (*v)[11]);
  }
  s.t[21] = s.t[20];
  for (int i = 0; i < 3; ++i) s.g[i][21] = 1e3;
  WriteText("run.csv", GyroCsv(s));
  RunWarnings w;
  const RunData d =
      LoadRunData(Describe(std::string(kGyroYaml) +
                           "data_format: {sort_by_time: true}\ntime_range_s: [0.045, 5.005]\n"),
                  &w);
  ASSERT_EQ(d.size(), 495u);  // t = 0.05 .. 5.00, one repeat dropped
  for (std::size_t k = 0; k < d.size(); ++k) {
    const std::size_t j = static_cast<std::size_t>(std::lround(d.t_s[k] / 0.01));
    ASSERT_NE(j, 21u);
    for (int i = 0; i < 3; ++i) ASSERT_EQ(d.gyro_rad_s[i][k], r.g[i][j] * kDegToRad) << k;
    ASSERT_EQ(d.w_mV[0][k], r.w[0][j]) << k;
  }
}

TEST_F(GyroInputTest, CsvRoundTripWritesTheGyroColumnsLast) {
  RunWarnings w;
  WriteText("run.csv", GyroCsv(MakeGyroRun(1.0)));
  const RunDescription run = Describe(kGyroYaml);
  const RunData data = LoadRunData(run, &w);
  WriteRunCsv(data, Path("back.csv"), "");
  EXPECT_EQ(ReadFile(Path("back.csv")).rfind("t,lambda1,lambda2,wx,wy,wz,gx,gy,gz\n", 0), 0u);
  RunDescription again = run;
  again.data_path = Path("back.csv");
  const RunData back = LoadRunData(again, &w);
  ASSERT_EQ(back.size(), data.size());
  for (std::size_t k = 0; k < data.size(); ++k) {
    for (int i = 0; i < 3; ++i) {
      ASSERT_NEAR(back.gyro_rad_s[i][k], data.gyro_rad_s[i][k],
                  1e-15 * std::abs(data.gyro_rad_s[i][k]))
          << k;
    }
  }
}

}  // namespace
}  // namespace triadcal

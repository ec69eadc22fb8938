// Units of the readings on input (column_mapping.h): m/s^2, g, mg, V, mV and
// raw counts with their count scale, and the output units named for what was
// read (counts/g when the readings are counts).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/io/run_description_io.h"
#include "core/io/run_io.h"
#include "core/model/errors.h"
#include "core/model/parameters.h"
#include "core/model/units.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

class InputUnitsTest : public testing_fixtures::TempDirTest {
 protected:
  // A bench-like run: the readings follow gravity as lambda1 turns (in g).
  void WriteRun(double per_g, double bias) const {
    std::string text = "t,lambda1,lambda2,ax,ay,az\n";
    for (int k = 0; k < 200; ++k) {
      const double l1 = 3.0 * k;  // deg
      const double c = std::cos(l1 * kDegToRad), s = std::sin(l1 * kDegToRad);
      text += FormatDouble(0.01 * k) + "," + FormatDouble(l1) + ",0," +
              FormatDouble(bias + per_g * c) + "," + FormatDouble(bias + per_g * 0.01 * k / 2) +
              "," + FormatDouble(bias - per_g * s) + "\n";
    }
    WriteText("run.csv", text);
  }
  std::string ErrorOf(const std::string& yaml) const {
    try {
      LoadRunDescription(WriteText("run.yaml", yaml));
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(InputUnitsTest, CountsKeepTheirScaleAndNameTheOutputUnits) {
  WriteRun(16384.0, 0.0);
  const RunDescription run = LoadRunDescription(
      WriteText("run.yaml",
                "data: run.csv\ncolumns:\n  wx: {source: ax, unit: counts, counts_per_g: 16384}\n"
                "  wy: {source: ay, unit: counts, counts_per_g: 16000}\n"
                "  wz: {source: az, unit: counts, counts_per_g: 16384}\n"));
  EXPECT_EQ(run.scale_mV_per_g[0], 16384.0);
  EXPECT_EQ(run.scale_mV_per_g[1], 16000.0);
  EXPECT_EQ(run.bias_mV[0], 0.0);
  EXPECT_EQ(ReadingsUnit(run), "counts");
  RunWarnings w;
  const RunData data = LoadRunData(run, &w);
  EXPECT_EQ(data.w_mV[0][0], 16384.0);  // counts stay counts
  const ParameterLayout layout({}, /*gyro=*/false, ReadingsUnit(run));
  EXPECT_EQ(layout.readings_unit(), "counts");
  EXPECT_EQ(layout.info(kKx).unit, "counts/g");
  EXPECT_EQ(layout.info(kW0x).unit, "counts");
  EXPECT_EQ(layout.info(kAlphaX).unit, "arcmin");
  EXPECT_EQ(layout.WithGyro(true).info(kKx).unit, "counts/g");  // the unit goes along
  // A value of the layout: another layout made afterwards names mV.
  EXPECT_EQ(ParameterLayout().info(kKx).unit, "mV/g");
}

TEST_F(InputUnitsTest, MetresPerSecondSquaredAtStandardGravity) {
  WriteRun(kStandardGravity, 0.0);
  const RunDescription run = LoadRunDescription(WriteText(
      "run.yaml",
      "data: run.csv\ncolumns:\n  wx: {source: ax, unit: m/s^2}\n  wy: {source: ay, unit: "
      "\"m/s\xC2\xB2\"}\n  wz: {source: az, unit: m/s^2}\n"));
  EXPECT_EQ(run.scale_mV_per_g[0], 1000.0);
  EXPECT_EQ(ReadingsUnit(run), "mg");
  RunWarnings w;
  const RunData data = LoadRunData(run, &w);
  EXPECT_NEAR(data.w_mV[0][0], 1000.0, 1e-9);  // 1 g read as 9.80665 m/s^2 -> 1000 mg
}

TEST_F(InputUnitsTest, CountsNeedTheirScaleAndCannotBeMixed) {
  const std::string y = Path("run.yaml");
  EXPECT_EQ(ErrorOf("data: run.csv\ncolumns: {wx: {source: ax, unit: counts}}\n"),
            y + ": columns.wx: readings in counts need their count scale: counts_per_g (e.g. "
                "16384)");
  EXPECT_EQ(ErrorOf("data: run.csv\ncolumns: {wx: {source: ax, unit: g, counts_per_g: 5}}\n"),
            y + ": columns.wx.counts_per_g: only with unit: counts");
  EXPECT_EQ(
      ErrorOf("data: run.csv\ncolumns: {wx: {source: ax, unit: counts, counts_per_g: 100}}\n"),
      y + ": columns: readings in counts and in other units cannot be mixed (give all three in "
          "counts)");
  EXPECT_EQ(ErrorOf("data: run.csv\ncolumns: {wx: {source: ax, unit: furlongs}}\n"),
            y + ": columns.wx.unit: unknown unit 'furlongs' for wx (allowed: mV, V, g, mg, "
                "m/s^2, m/s\xC2\xB2, counts)");
}

}  // namespace
}  // namespace triadcal

// Bad input at the command line (issue 16, groups 1-5): each case gives exit 2,
// exactly one line on stderr naming the file, line or key and the bound, and
// no output file. The cases run the built `triadcal` on a small simulated run
// of the paper's profile, each with one thing broken.
#include <gtest/gtest.h>
#include <matio.h>
#include <sys/wait.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/model/parameters.h"
#include "core/simulation/simulator.h"
#include "tests/sim_fixtures.h"
#include "tests/cli_test.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::CliResult;

class CliInputErrors : public testing_fixtures::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    lines_ = ReadLines(Path("run.csv"));
  }

  static std::vector<std::string> ReadLines(const std::string& path) {
    std::ifstream in(path);
    std::vector<std::string> out;
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  }

  // run.csv with line `line` (1-based; 1 is the header) replaced by `text`.
  std::string CsvWithLine(int line, const std::string& text) const {
    std::string s;
    for (int i = 0; i < static_cast<int>(lines_.size()); ++i) {
      s += (i + 1 == line ? text : lines_[i]) + "\n";
    }
    return WriteText("bad.csv", s);
  }

  // Field `field` (0-based) of data line `line` set to `value`.
  std::string CsvWithField(int line, int field, const std::string& value) const {
    std::stringstream ss(lines_[line - 1]);
    std::vector<std::string> f;
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    f[field] = value;
    std::string row;
    for (std::size_t i = 0; i < f.size(); ++i) row += (i ? "," : "") + f[i];
    return CsvWithLine(line, row);
  }

  std::string FitBad(const std::string& yaml_text) const {
    return "fit " + WriteText("bad.yaml", yaml_text) + " -o " + Path("out.json");
  }

  std::vector<std::string> lines_;
};

// ---- group 1: non-finite arithmetic never reaches Ceres

TEST_F(CliInputErrors, HugeTimeStampIsRefused) {
  const int last = static_cast<int>(lines_.size());
  const std::string csv = CsvWithField(last, 0, "1e300");
  ExpectError(FitBad("data: bad.csv\n"),
              csv + ":" + std::to_string(last) +
                  ": column 't': 1e+300 s is beyond the bound |t| <= 1e+11 s (3000 years)");
}

TEST_F(CliInputErrors, HugeReadingIsRefused) {
  const std::string csv = CsvWithField(40, 4, "1e300");
  ExpectError(FitBad("data: bad.csv\n"),
              csv +
                  ":40: column 'wy': 1e+300 is 5.747e+297 g from the nominal bias at the "
                  "nominal scale 174 per g (bound 1000 g): check columns.wy.unit and "
                  "triad.scale_mV_per_g");
}

TEST_F(CliInputErrors, HugeAngleInOneRowIsRefused) {
  const std::string csv = CsvWithField(40, 1, "1e300");
  ExpectError(FitBad("data: bad.csv\n"),
              csv + ":40: column 'lambda1': 1e+300 deg is beyond the bound |angle| <= 1e+07 deg");
}

TEST_F(CliInputErrors, WildAngleInOneRowIsRefused) {
  const std::string csv = CsvWithField(40, 2, "5000");
  const CliResult r = Run(FitBad("data: bad.csv\n"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("triadcal: error: " + csv + ":40: column 'lambda2': jumps by ", 0), 0u)
      << r.err;
  EXPECT_NE(r.err.find("beyond the bound 3600 deg/s (10 turns per second): a wild angle, or "
                       "the time unit is wrong\n"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

TEST_F(CliInputErrors, ImplausibleNumbersInRunYaml) {
  const std::string y = Path("bad.yaml");
  ExpectError(FitBad("data: run.csv\ntriad: {noise_mV: 1e300}\n"),
              y + ": triad.noise_mV: 1e+300 is outside [1e-07, 1] g worth of the nominal scale "
                  "(1.74e-05 to 174): no accelerometer is quieter than 0.1 ug per sample, and a "
                  "noise of 1 g leaves nothing to calibrate");
  ExpectError(FitBad("data: run.csv\ntriad: {noise_mV: 1e-300}\n"),
              y + ": triad.noise_mV: 1e-300 is outside [1e-07, 1] g worth of the nominal scale "
                  "(1.74e-05 to 174): no accelerometer is quieter than 0.1 ug per sample, and a "
                  "noise of 1 g leaves nothing to calibrate");
  ExpectError(FitBad("data: run.csv\ntriad: {scale_mV_per_g: [174, 1e300, 174]}\n"),
              y + ": triad.scale_mV_per_g[1]: 1e+300 is outside [0.001, 1e+08] per g (no "
                  "accelerometer output is outside this range)");
  ExpectError(FitBad("data: run.csv\nbench: {g_mps2: 1e300}\n"),
              y + ": bench.g_mps2: 1e+300 m/s^2 is outside [9.7, 9.9] (gravity on the Earth's "
                  "surface; the unit is m/s^2)");
  ExpectError(FitBad("data: run.csv\nbench: {g_mps2: 1}\n"),
              y + ": bench.g_mps2: 1 m/s^2 is outside [9.7, 9.9] (gravity on the Earth's "
                  "surface; the unit is m/s^2)");
  ExpectError(FitBad("data: run.csv\nbench: {angle_noise_arcsec: 1e300}\n"),
              y + ": bench.angle_noise_arcsec: 1e+300 arcsec is beyond the bound 3600 arcsec (an "
                  "angle sensor worse than 1 deg cannot calibrate arcminutes)");
}

TEST_F(CliInputErrors, ConstraintCoefficientOrSigmaThatHoldsEverything) {
  const std::string y = Path("bad.yaml");
  ExpectError(
      FitBad("data: run.csv\nconstraints:\n  - {expr: \"1e300*dpsi - dlambda2\", sigma_arcsec: "
             "30}\n"),
      y + ": constraints[0] (\"1e300*dpsi - dlambda2\"): coefficients too large: the "
          "combination's prior scale overflows (bound: finite)");
  ExpectError(
      FitBad("data: run.csv\nconstraints:\n  - {expr: \"dpsi - dlambda2\", sigma_arcsec: "
             "1e-300}\n"),
      y + ": constraints[0] (\"dpsi - dlambda2\"): sigma 1.667e-302 arcmin is 6.547e-305 of the "
          "combination's prior scale 254.6 arcmin (bound: at least 1e-6; tighter holds "
          "everything and ruins the conditioning)");
  ExpectError(FitBad("data: run.csv\npriors: {Kx: 1e-300}\n"),
              y + ": priors.Kx: 1e-300 mV/g is 5.747e-302 times the default 17.4 mV/g (bound: "
                  "between 1e-6 and 1e6 times; beyond, the prior either fixes the parameter or "
                  "adds nothing, and ruins the conditioning)");
}

// ---- group 2: plausibility, units that look wrong

TEST_F(CliInputErrors, LeverArmInMicrometres) {
  ExpectError(FitBad("data: run.csv\nbench: {lever_arm_mm: [1e9, 20, 20]}\n"),
              Path("bad.yaml") +
                  ": bench.lever_arm_mm[0]: 1e+09 mm is beyond the bound |R0| <= 2000 mm (a bench "
                  "platform is smaller than 2 m; is it in m or um?)");
}

TEST_F(CliInputErrors, TimeInMillisecondsDeclaredAsSeconds) {
  WriteText("ms.yaml", "data: run.csv\ncolumns: {t: {source: t, scale: 1000}}\n");
  ExpectError("fit " + Path("ms.yaml") + " -o " + Path("out.json"),
              Path("run.csv") +
                  ": column 't': median sample interval 20 s is beyond the bound 0.5 s (the "
                  "bench swings with periods of seconds): is the time in ms? set columns.t.unit: "
                  "ms");
}

TEST_F(CliInputErrors, AnglesInRadiansOverALongRun) {
  // The paper's profile (360 deg outer amplitude) in radians spans 4 pi "deg":
  // more than the 2 pi + 0.1 of the short-run test; the windows still see it.
  WriteText("rad.yaml",
            "data: run.csv\ncolumns: {lambda1: {source: lambda1, scale: 0.0174532925199432958},"
            " lambda2: {source: lambda2, scale: 0.0174532925199432958}}\n");
  const CliResult r = Run("fit " + Path("rad.yaml") + " -o " + Path("out.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(
      r.err.rfind(
          "triadcal: error: " + Path("run.csv") + ": column 'lambda1', column 'lambda2': in ", 0),
      0u)
      << r.err;
  EXPECT_NE(r.err.find("the angles look like radians, not degrees; set columns.lambda1.unit and "
                       "columns.lambda2.unit to rad\n"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

// The other side of the check above: a run in degrees whose readings are
// noisy (vibration: 60 mV = 0.34 g per sample on 174 mV/g) swings by more
// than 0.5 g in every window; it is judged against the readings' own noise
// (second differences), so noise_mV: auto, which declares no figure, loads.
TEST_F(CliInputErrors, NoisyRunInDegreesIsNotTakenForRadians) {
  const Scenario s = testing_fixtures::PaperScenario(50.0, 20.0, 60.0, 15.0, 11);
  WriteRunCsv(Simulate(s), Path("noisy.csv"), "");
  WriteText("noisy.yaml", "data: noisy.csv\ntriad: {noise_mV: auto}\n");
  const CliResult r = Run("fit " + Path("noisy.yaml") + " -o " + Path("out.json") + " -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("radians"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(Path("out.json")));
}

// A mistyped command is named with the nearest one; a list option's items
// may have blanks around them.
TEST_F(CliInputErrors, UnknownCommandIsNamedWithTheNearest) {
  ExpectError("fitt " + Path("run.yaml") + " -o " + Path("out.json"),
              "unknown command 'fitt' (did you mean 'fit'?) (see `triadcal --help`)");
  ExpectError("frobnicate", "unknown command 'frobnicate' (see `triadcal --help`)");
  const CliResult r = Run("fit " + Path("run.yaml") + " -o " + Path("out.json") +
                          " -q --effects 'angle_latency, thermal_drift'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(CliInputErrors, ReadingsInMillivoltsDeclaredAsG) {
  WriteText("g.yaml",
            "data: run.csv\ncolumns: {wx: {source: wx, unit: g}, wy: {source: wy, unit: g}, "
            "wz: {source: wz, unit: g}}\n");
  const CliResult r = Run("fit " + Path("g.yaml") + " -o " + Path("out.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("triadcal: error: " + Path("run.csv") + ":2: column 'wx': ", 0), 0u)
      << r.err;
  EXPECT_NE(r.err.find("g from the nominal bias at the nominal scale 1000 per g (bound 1000 g): "
                       "check columns.wx.unit and triad.scale_mV_per_g\n"),
            std::string::npos)
      << r.err;
}

// ---- group 3: rows that do not match the header

TEST_F(CliInputErrors, DecimalCommaShiftsTheColumns) {
  const std::string csv = CsvWithField(30, 3, "1504,2");
  ExpectError(FitBad("data: bad.csv\n"),
              csv + ":30: 7 fields, but the header (line 1) has 6 (a decimal comma?)");
}

TEST_F(CliInputErrors, DuplicateColumnName) {
  const std::string csv = CsvWithLine(1, "t,lambda1,lambda2,wx,wy,wx");
  ExpectError(FitBad("data: bad.csv\n"),
              csv +
                  ":1: column 'wx' appears twice (fields 4 and 6); rename one, or name the "
                  "columns with data_format.header");
}

// ---- group 4: damaged MAT files

void WriteMat(const std::string& path, const std::vector<std::vector<double>>& columns,
              matio_compression compression) {
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  ASSERT_NE(mat, nullptr);
  const char* names[] = {"t", "lambda1", "lambda2", "wx", "wy", "wz"};
  for (int v = 0; v < 6; ++v) {
    std::size_t dims[2] = {columns[v].size(), 1};
    matvar_t* var = Mat_VarCreate(names[v], MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims,
                                  const_cast<double*>(columns[v].data()), MAT_F_DONT_COPY_DATA);
    Mat_VarWrite(mat, var, compression);
    Mat_VarFree(var);
  }
  Mat_Close(mat);
}

TEST_F(CliInputErrors, TruncatedMatFileSaysDamaged) {
  const RunData d = Simulate(testing_fixtures::PaperScenario(50.0, 20.0, 2.0, 15.0, 11));
  std::vector<std::vector<double>> cols = {d.t_s,     d.lambda_rad[0], d.lambda_rad[1],
                                           d.w_mV[0], d.w_mV[1],       d.w_mV[2]};
  for (double& x : cols[1]) x /= 0.0174532925199432958;
  for (double& x : cols[2]) x /= 0.0174532925199432958;
  for (const matio_compression c : {MAT_COMPRESSION_NONE, MAT_COMPRESSION_ZLIB}) {
    const std::string full = Path("full.mat");
    WriteMat(full, cols, c);
    const std::string text = ReadFile(full);
    WriteText("cut.mat", text.substr(0, text.size() * 9 / 10));
    const CliResult r = Run(FitBad("data: cut.mat\n"));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("triadcal: error: " + Path("cut.mat") + ": damaged MATLAB file (", 0), 0u)
        << r.err;
    EXPECT_FALSE(fs::exists(Path("out.json")));
  }
}

TEST_F(CliInputErrors, MatHeaderClaimingBillionsOfSamples) {
  // One variable whose dimensions say 1 x 2e9 in a file of a few hundred bytes:
  // the declared size is checked against the file before matio allocates it.
  std::vector<double> x(16, 1.0);
  std::size_t dims[2] = {16, 1};
  mat_t* mat = Mat_CreateVer(Path("huge.mat").c_str(), nullptr, MAT_FT_MAT5);
  matvar_t* var = Mat_VarCreate("t", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, x.data(), 0);
  Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE);
  Mat_VarFree(var);
  Mat_Close(mat);
  std::string bytes = ReadFile(Path("huge.mat"));
  // v5 layout: header 128, matrix tag 8, flags 16, dims tag 8, dims 2 x int32.
  const std::size_t dims_at = 128 + 8 + 16 + 8;
  const std::int32_t big = 2000000000;
  std::memcpy(&bytes[dims_at], &big, 4);
  WriteText("huge.mat", bytes);
  const CliResult r = Run(FitBad("data: huge.mat\n"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, "triadcal: error: " + Path("huge.mat") +
                       ": damaged MATLAB file (variable 't' declares 2000000000x1 values, more "
                       "than the " +
                       std::to_string(bytes.size()) + "-byte file can hold)\n");
}

// ---- group 5: data loss and silent nonsense elsewhere

std::string CalibrationJson(double kxx, const std::string& kx_text = "174") {
  std::string p = "{\"parameters\": {\"Kx\": " + kx_text + ", \"Ky\": 174, \"Kz\": 174";
  for (const char* b : {"W0x", "W0y", "W0z"}) p += std::string(", \"") + b + "\": 1500";
  for (const char* a : {"alpha_x", "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z"}) {
    p += std::string(", \"") + a + "\": 0";
  }
  for (const char* k : {"Kxy", "Kxz", "Kyx", "Kyy", "Kyz", "Kzx", "Kzy", "Kzz"}) {
    p += std::string(", \"") + k + "\": 0";
  }
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", kxx);
  return p + ", \"Kxx\": " + buf + "}}";
}

TEST_F(CliInputErrors, ApplyNeverOverwritesItsInput) {
  const std::string cal = WriteText("cal.json", CalibrationJson(0.0));
  const std::string before = ReadFile(Path("run.csv"));
  ExpectError("apply " + cal + " " + Path("run.yaml") + " -o " + Path("run.csv"),
              Path("run.csv") + ": is the input file '" + Path("run.csv") +
                  "' (an output never replaces an input; choose another name)",
              {});
  EXPECT_EQ(ReadFile(Path("run.csv")), before);
  ExpectError("apply " + cal + " " + Path("run.yaml") + " -o " + Path("run.yaml"),
              Path("run.yaml") + ": is the input file '" + Path("run.yaml") +
                  "' (an output never replaces an input; choose another name)",
              {});
  ExpectError("apply " + cal + " " + Path("run.yaml") + " -o " + cal,
              cal + ": is the input file '" + cal +
                  "' (an output never replaces an input; choose another name)",
              {});
}

TEST_F(CliInputErrors, FitResidualsOntoTheDataFileWritesNothing) {
  ExpectError(
      "fit " + Path("run.yaml") + " -o " + Path("out.json") + " --residuals " + Path("run.csv"),
      Path("run.csv") + ": is the input file '" + Path("run.csv") +
          "' (an output never replaces an input; choose another name)");
}

// The jobs and commands note what they load into the session's guard (core's
// readers note nothing): each kind of input, as every command that reads it
// takes it, is refused as an output, and left as it was.
TEST_F(CliInputErrors, EveryKindOfInputIsRefusedAsAnOutput) {
  const std::string scenario = WriteText(
      "scenario.yaml", "profile: {duration_s: 2, rate_hz: 20}\nrun: {triad: {noise_mV: 2}}\n");
  fs::copy_file(Path("run.csv"), Path("run2.csv"));
  WriteText("run2.yaml", "data: run2.csv\n");
  const std::string runs = WriteText(
      "runs.yaml", "runs:\n  - {name: a, run: run.yaml}\n  - {name: b, run: run2.yaml}\n");
  ASSERT_EQ(Run("fit " + Path("run.yaml") + " -o " + Path("fit.json")).exit_code, 0);
  for (const char* shard : {"1/2", "2/2"}) {
    ASSERT_EQ(Run("montecarlo " + scenario + " -n 2 --shard " + shard + " -o " +
                  Path(std::string("shard") + shard[0] + ".json"))
                  .exit_code,
              0);
  }
  const std::string fit = Path("fit.json"), shard = Path("shard2.json");
  const struct {
    std::string args, input;
  } cases[] = {
      {"fit " + runs + " -o " + runs, runs},                            // a runs file
      {"observability " + runs + " -o " + runs, runs},                  // the same
      {"fit " + runs + " -o " + Path("run2.yaml"), Path("run2.yaml")},  // a run of it
      {"observability " + scenario + " -o " + scenario, scenario},      // a scenario
      {"design " + scenario + " -o " + scenario, scenario},
      {"montecarlo " + scenario + " -n 2 -o " + scenario, scenario},
      {"observability " + Path("run.yaml") + " --at " + fit + " -o " + fit, fit},  // --at
      {"export " + fit + " --format yaml -o " + fit, fit},                         // a calibration
      {"report " + fit + " -o " + fit, fit},                                       // a report's OUT
      {"merge " + Path("shard1.json") + " " + shard + " -o " + shard, shard},      // a shard
  };
  for (const auto& c : cases) {
    const std::string before = ReadFile(c.input);
    ExpectError(c.args,
                c.input + ": is the input file '" + c.input +
                    "' (an output never replaces an input; choose another name)",
                {});
    EXPECT_EQ(ReadFile(c.input), before) << c.args;
  }
}

TEST_F(CliInputErrors, TwoOutputsOneFile) {
  ExpectError(
      "filter " + Path("run.yaml") + " -o " + Path("out.json") + " --series " + Path("out.json"),
      Path("out.json") + ": given for two outputs (each output needs its own file)");
}

TEST_F(CliInputErrors, ApplyWithoutARealInverse) {
  // u = W + Kxx W^2 with Kxx = -1/g peaks at u = 0.25 g: readings of 1 g have
  // no real W, and Newton's last iterate must not be written.
  const std::string cal = WriteText("cal.json", CalibrationJson(-1.0));
  const CliResult r = Run("apply " + cal + " " + Path("run.yaml") + " -o " + Path("w.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("triadcal: error: " + cal +
                            ": the calibration has no real inverse for "
                            "sample ",
                        0),
            0u)
      << r.err;
  EXPECT_NE(r.err.find("its nonlinearity K_ij folds the readings model there (is the "
                       "calibration from this sensor, in these units?)\n"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(Path("w.csv")));
}

TEST_F(CliInputErrors, JsonNumberOutOfRange) {
  const std::string cal = WriteText("cal.json", CalibrationJson(0.0, "1e309"));
  const CliResult r = Run("apply " + cal + " " + Path("run.yaml") + " -o " + Path("w.csv"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("triadcal: error: " + cal + ": not valid JSON: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("1e309"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("w.csv")));
}

TEST_F(CliInputErrors, EpochOutOfBounds) {
  ExpectError(
      "fit " + Path("run.yaml") + " -o " + Path("out.json") + " --epoch-s 1e-9",
      "--epoch-s: Value 1e-9 not in range 0.010000 to 10.000000 (see `triadcal fit --help`)");
}

TEST_F(CliInputErrors, YamlKeysThatAreNotNames) {
  ExpectError(
      FitBad("data: run.csv\npriors: {[a, b]: 1}\n"),
      Path("bad.yaml") + ": priors: expected a name as key, got a list (a list or map is no key)");
  ExpectError(FitBad("data: run.csv\n? [bench]\n: 1\n"),
              Path("bad.yaml") + ": expected a name as key, got a list (a list or map is no key)");
}

TEST_F(CliInputErrors, SimulateRefusesRunsTooShortToUse) {
  const std::string sc = WriteText("sc.yaml", "profile: {duration_s: 0.01, rate_hz: 100}\n");
  ExpectError("simulate " + sc + " -o " + Path("sim"),
              sc + ": profile: duration_s * rate_hz = 1 samples; a run needs at least 10", {"sim"});
}

TEST_F(CliInputErrors, DesignLeavesNothingWhenItsJsonFails) {
  // OUT is a folder: the JSON cannot be written, and nothing else (the SVG of
  // older versions, OUT with .svg) is left behind either.
  const std::string sc = WriteText("sc.yaml", "profile: {duration_s: 20, rate_hz: 20}\n");
  fs::create_directories(Path("out.json"));
  ExpectError("design " + sc + " -o " + Path("out.json") + " --durations 10,20",
              Path("out.json") + ": cannot write: is a directory", {"out.svg"});
}

TEST_F(CliInputErrors, ControlCharactersAreEscaped) {
  const std::string csv = CsvWithField(12, 3, "1\x1b[2J");
  ExpectError(FitBad("data: bad.csv\n"), csv + ":12: column 'wx': not a number: '1\\x1B[2J'");
}

TEST_F(CliInputErrors, CommandLineSyntaxIsOneLine) {
  ExpectError("fit", "run is required (see `triadcal fit --help`)", {});
  ExpectError("fit " + Path("run.yaml") + " -o " + Path("out.json") + " --no-such-option",
              "The following argument was not expected: --no-such-option (see `triadcal fit "
              "--help`)");
}

TEST_F(CliInputErrors, OptionsOfTheOldSolverPathsAreGone) {
  // One solver path (batch_minimizer.h): no linear-solver, covariance or
  // robust-loss choice left to make. Under the sanitizer build this also
  // checks that nothing leaks on the way out.
  for (const char* option : {"--robust", "--linear-solver", "--covariance"}) {
    ExpectError("fit " + Path("run.yaml") + " -o " + Path("out.json") + " " + option + " x",
                std::string("The following argument was not expected: ") + option +
                    " (see `triadcal fit --help`)");
  }
}

TEST_F(CliInputErrors, ReflectionMountingIsAnError) {
  ExpectError(FitBad("data: run.csv\nmounting: {axes: [\"+x\", \"+y\", \"-z\"]}\n"),
              Path("bad.yaml") +
                  ": mounting.axes: [+x, +y, -z] is a reflection (determinant -1), not a "
                  "rotation: flip the sign of one axis (e.g. [+x, +y, +z])");
}

}  // namespace
}  // namespace triadcal

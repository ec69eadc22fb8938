// Tests of run data in and out (core/io/run_io.h): the CSV round trip, what the
// text reader ignores, unwrapping, every bad input with its exact error text,
// the counted warnings, MATLAB files through matio with a column mapping and a
// mounting, and the real single-axis runs of examples/single-axis-roll.
#include <gtest/gtest.h>
#include <matio.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/model/errors.h"
#include "tests/temp_dir_test.h"
#include "core/io/file_util.h"
#include "core/model/run_description.h"
#include "core/io/run_io.h"
#include "core/model/units.h"
#include "core/io/run_description_io.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

class RunIoTest : public testing_fixtures::TempDirTest {
 protected:



  // A run description in code: the defaults of run.yaml and this data file.
  RunDescription Describe(const std::string& data_name) const {
    RunDescription run;
    run.yaml_path = Path("run.yaml");
    run.data_path = Path(data_name);
    return run;
  }

  // A run description read from YAML text written to run.yaml.
  RunDescription DescribeYaml(const std::string& yaml) const {
    return LoadRunDescription(WriteText("run.yaml", yaml));
  }

  // The InputError text of loading data_name with the default description.
  std::string ErrorOf(const RunDescription& run) const {
    try {
      RunWarnings w;
      LoadRunData(run, &w);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
  std::string CsvError(const std::vector<std::string>& lines) const {
    std::string text;
    for (const std::string& l : lines) text += l + "\n";
    WriteText("run.csv", text);
    return ErrorOf(Describe("run.csv"));
  }

};

// A plausible run: 1.5 kHz-like smooth values with no repeats, rates and temp.
RunData MakeRun(std::size_t n, bool rates, bool temp) {
  RunData r;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 0.01 * static_cast<double>(k);
    r.t_s.push_back(t);
    r.lambda_rad[0].push_back(2.0 * kPi * std::sin(2.0 * kPi * t / 3.0) + 0.3);
    r.lambda_rad[1].push_back(0.5 * kPi * std::sin(2.0 * kPi * t / 1.2));
    for (int i = 0; i < 3; ++i) {
      r.w_mV[i].push_back(1500.0 + 174.0 * std::cos(r.lambda_rad[0].back() + i) + 1e-3 * t);
    }
    if (rates) {
      r.rate_rad_s[0].push_back(4.0 * kPi * kPi / 3.0 * std::cos(2.0 * kPi * t / 3.0));
      r.rate_rad_s[1].push_back(kPi * kPi / 1.2 * std::cos(2.0 * kPi * t / 1.2));
    }
    if (temp) r.temp_C.push_back(25.0 + 0.0123 * t);
  }
  return r;
}

void ExpectSameRun(const RunData& a, const RunData& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.has_rates(), b.has_rates());
  ASSERT_EQ(a.has_temp(), b.has_temp());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a.t_s[k], b.t_s[k]) << k;
    for (int i = 0; i < 2; ++i) {
      ASSERT_NEAR(a.lambda_rad[i][k], b.lambda_rad[i][k], 1e-15 * std::abs(a.lambda_rad[i][k]))
          << k;
      if (a.has_rates()) {
        ASSERT_NEAR(a.rate_rad_s[i][k], b.rate_rad_s[i][k], 1e-15 * std::abs(a.rate_rad_s[i][k]))
            << k;
      }
    }
    for (int i = 0; i < 3; ++i) ASSERT_EQ(a.w_mV[i][k], b.w_mV[i][k]) << k;
    if (a.has_temp()) {
      ASSERT_EQ(a.temp_C[k], b.temp_C[k]) << k;
    }
  }
}

// Lines of a valid CSV with n rows: row k is on file line k + 2.
std::vector<std::string> GoodCsv(int n) {
  std::vector<std::string> lines = {"t,lambda1,lambda2,wx,wy,wz"};
  for (int k = 0; k < n; ++k) {
    lines.push_back(FormatDouble(k / 100.0) + "," + std::to_string(10 * k) + "," +
                    std::to_string(5 * k - 20) + "," + std::to_string(1500 + 3 * k) + "," +
                    std::to_string(1400 - 2 * k) + "," + std::to_string(1600 + k % 7));
  }
  return lines;
}

TEST_F(RunIoTest, CsvRoundTripIsExact) {
  for (bool extras : {false, true}) {
    const RunData run = MakeRun(1000, extras, extras);
    WriteRunCsv(run, Path("run.csv"), "simulated\nsecond comment line");
    RunWarnings warnings;
    const RunData back = LoadRunData(Describe("run.csv"), &warnings);
    EXPECT_TRUE(warnings.lines.empty()) << warnings.lines.front();
    ExpectSameRun(run, back);
  }
  const std::string text = ReadFile(Path("run.csv"));
  EXPECT_EQ(text.rfind("# simulated\n# second comment line\n"
                       "t,lambda1,lambda2,wx,wy,wz,lambda1_rate,lambda2_rate,temp_C\n0,",
                       0),
            0u)
      << text.substr(0, 200);
  // Angles are written in degrees, exactly lambda_rad / kDegToRad.
  const RunData run = MakeRun(10, false, false);
  WriteRunCsv(run, Path("small.csv"), "");
  const std::string small = ReadFile(Path("small.csv"));
  const std::string row0 = "0," + FormatDouble(run.lambda_rad[0][0] / kDegToRad) + ",0,";
  EXPECT_EQ(small.find("t,lambda1,lambda2,wx,wy,wz\n" + row0), 0u) << small;
}

// The text reader reads in blocks of a few MB: a file of several blocks, with
// CRLF line ends and no final newline, reads back exactly, and an error in
// its last block names the right line.
TEST_F(RunIoTest, CsvOfSeveralReadBlocks) {
  const RunData run = MakeRun(120000, true, true);  // about 13 MB of text
  WriteRunCsv(run, Path("run.csv"), "long");
  std::string text = ReadFile(Path("run.csv"));
  ASSERT_GT(text.size(), 3u * (1u << 22));
  std::string crlf;
  crlf.reserve(text.size() + 130000);
  for (char c : text) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  crlf.resize(crlf.size() - 2);  // no final line end
  WriteText("crlf.csv", crlf);
  RunWarnings warnings;
  ExpectSameRun(run, LoadRunData(Describe("crlf.csv"), &warnings));
  // Line 119 990 of the data, the 2 comment and header lines before it.
  const std::size_t row = 119990;
  std::size_t at = 0;
  for (std::size_t k = 0; k < row + 2; ++k) at = crlf.find('\n', at) + 1;
  crlf.insert(at, "x");
  WriteText("bad.csv", crlf);
  EXPECT_EQ(ErrorOf(Describe("bad.csv")),
            Path("bad.csv") + ":" + std::to_string(row + 3) + ": column 't': not a number: 'x" +
                FormatDouble(run.t_s[row]) + "'");
}

// Past 64 KB the reader parses the lines it holds on two threads, split at a
// line end near the middle: the rows come back in order, comment and blank
// lines in the first half move the line numbers of the second, and an error
// names its file line in either half (the first half's when both have one).
// With one thread (--threads 1) the same run and the same errors.
TEST_F(RunIoTest, CsvParsedOnTwoThreads) {
  const RunData run = MakeRun(3000, false, false);
  WriteRunCsv(run, Path("run.csv"), "two halves");
  std::vector<std::string> lines;
  {
    const std::string text = ReadFile(Path("run.csv"));
    ASSERT_GT(text.size(), std::size_t{1} << 16);
    std::size_t at = 0;
    while (at < text.size()) {
      const std::size_t eol = text.find('\n', at);
      lines.push_back(text.substr(at, eol - at));
      at = eol + 1;
    }
  }
  lines.insert(lines.begin() + 100, "# a comment in the first half");
  lines.insert(lines.begin() + 200, "");
  auto write = [&](const std::string& name, const std::vector<std::string>& v) {
    std::string text;
    for (const std::string& l : v) text += l + "\n";
    WriteText(name, text);
  };
  write("halves.csv", lines);
  RunWarnings warnings;
  ExpectSameRun(run, LoadRunData(Describe("halves.csv"), &warnings));
  ExpectSameRun(run, LoadRunData(Describe("halves.csv"), &warnings, 1));
  // Errors: line index j is file line j + 1.
  auto spoil = [](std::string* line) {
    *line = "x" + *line;
    return line->substr(0, line->find(','));
  };
  std::vector<std::string> bad = lines;
  const std::size_t late = lines.size() - 50;
  const std::string late_t = spoil(&bad[late]);
  write("bad.csv", bad);
  EXPECT_EQ(ErrorOf(Describe("bad.csv")), Path("bad.csv") + ":" + std::to_string(late + 1) +
                                              ": column 't': not a number: '" + late_t + "'");
  const std::string early_t = spoil(&bad[150]);
  write("bad.csv", bad);
  EXPECT_EQ(ErrorOf(Describe("bad.csv")),
            Path("bad.csv") + ":151: column 't': not a number: '" + early_t + "'");
  try {
    LoadRunData(Describe("bad.csv"), &warnings, 1);
    ADD_FAILURE() << "bad.csv read on one thread without an error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              Path("bad.csv") + ":151: column 't': not a number: '" + early_t + "'");
  }
  // A check after reading names a second-half row by its file line too (the
  // rows keep their lines).
  std::vector<std::string> back = lines;
  back[late] = "0" + back[late].substr(back[late].find(','));
  write("back.csv", back);
  for (int threads : {0, 1}) {
    try {
      LoadRunData(Describe("back.csv"), &warnings, threads);
      ADD_FAILURE() << "back.csv read without an error";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(Path("back.csv") + ":" + std::to_string(late + 1) +
                                                ": ",
                                            0),
                0u)
          << e.what();
    }
  }
}

// One file column may feed two channels (the reader hands a column over to
// the last channel that reads it, and copies it for the others).
TEST_F(RunIoTest, OneColumnFeedsTwoChannels) {
  WriteText("run.csv", [] {
    std::string t;
    for (const std::string& l : GoodCsv(40)) t += l + "\n";
    return t;
  }());
  RunDescription run = DescribeYaml("data: run.csv\ncolumns:\n  wz: {source: wy}\n");
  RunWarnings warnings;
  const RunData data = LoadRunData(run, &warnings);
  ASSERT_EQ(data.size(), 40u);
  for (std::size_t k = 0; k < data.size(); ++k) {
    ASSERT_EQ(data.w_mV[1][k], 1400.0 - 2.0 * static_cast<double>(k)) << k;
    ASSERT_EQ(data.w_mV[2][k], data.w_mV[1][k]) << k;
  }
}

// time_range_s keeps the samples with from <= t <= to; a range without
// samples, or backwards, is an error naming the key.
TEST_F(RunIoTest, TimeRangeKeepsPartOfTheRun) {
  const RunData run = MakeRun(3000, false, false);  // t = 0 .. 29.99 s
  WriteRunCsv(run, Path("run.csv"), "");
  RunWarnings w;
  const RunData part =
      LoadRunData(DescribeYaml("data: run.csv\ntime_range_s: [10, 20]\n"), &w);
  ASSERT_EQ(part.size(), 1001u);
  EXPECT_NEAR(part.t_s.front(), 10.0, 1e-9);
  EXPECT_NEAR(part.t_s.back(), 20.0, 1e-9);
  EXPECT_EQ(ErrorOf(DescribeYaml("data: run.csv\ntime_range_s: [40, 50]\n")),
            Path("run.yaml") + ": time_range_s: [40, 50] s holds 0 sample(s); the run spans 0 to 29.99 s");
  try {
    DescribeYaml("data: run.csv\ntime_range_s: [20, 10]\n");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              Path("run.yaml") + ": time_range_s: from must be before to, got [20, 10]");
  }
}

TEST_F(RunIoTest, CommentsBlankLinesAndOtherColumnsAreIgnored) {
  std::string text = "# recorded 2016-03-01\n  # indented comment\n\n";
  text += "note, wz ,t,lambda1,extra,lambda2,wx,wy,temp_C\r\n";
  for (int k = 0; k < 12; ++k) {
    if (k == 5) text += "# operator left the room\n\n";
    text += "text " + std::to_string(k) + "," + std::to_string(1600 + k) + "," +
            FormatDouble(k * 0.01) + ",+" + std::to_string(10 * k) + ",x," +
            std::to_string(-3 * k) + ", 1.5e3 ," + FormatDouble(1400.25 + k) + "," +
            std::to_string(20 + k) + "\r\n";
  }
  WriteText("run.csv", text);
  RunWarnings warnings;
  const RunData data = LoadRunData(Describe("run.csv"), &warnings);
  ASSERT_EQ(warnings.lines.size(), 1u);  // wx held at 1500 mV: a dead channel?
  EXPECT_EQ(warnings.lines[0],
            "column 'wx': every sample is 1500 while the bench turns: a dead channel or a "
            "damaged file");
  ASSERT_EQ(data.size(), 12u);
  EXPECT_FALSE(data.has_rates());
  ASSERT_TRUE(data.has_temp());
  EXPECT_EQ(data.t_s[11], 0.11);
  EXPECT_EQ(data.lambda_rad[0][3], 30.0 * kDegToRad);
  EXPECT_EQ(data.lambda_rad[1][3], -9.0 * kDegToRad);
  EXPECT_EQ(data.w_mV[0][7], 1500.0);
  EXPECT_EQ(data.w_mV[1][7], 1407.25);
  EXPECT_EQ(data.w_mV[2][7], 1607.0);
  EXPECT_EQ(data.temp_C[7], 27.0);
}

TEST_F(RunIoTest, WhitespaceSeparatedText) {
  std::string text = "# t in s\nt\tlambda1  lambda2 wx wy wz\n";
  for (int k = 0; k < 10; ++k) {
    text += "  " + FormatDouble(k * 0.5) + "\t" + std::to_string(40 * k) + "   0 1500 1501 " +
            std::to_string(1490 + k) + "\n";
  }
  WriteText("run.txt", text);
  RunWarnings warnings;
  const RunData data = LoadRunData(Describe("run.txt"), &warnings);
  ASSERT_EQ(data.size(), 10u);
  EXPECT_EQ(data.t_s[9], 4.5);
  EXPECT_EQ(data.lambda_rad[0][9], 360.0 * kDegToRad);
  EXPECT_EQ(data.w_mV[2][9], 1499.0);
}

TEST_F(RunIoTest, WrappedAnglesAreUnwrapped) {
  // lambda1 turns steadily through two turns, recorded in [0, 360); lambda2
  // swings through +-180, recorded in (-180, 180].
  std::string text = "t,lambda1,lambda2,wx,wy,wz\n";
  std::vector<double> l1_true, l2_true;
  for (int k = 0; k < 100; ++k) {
    const double l1 = 7.5 * k, l2 = 150.0 + 2.0 * k * (k < 50 ? 1 : -1) + (k < 50 ? 0 : 200);
    l1_true.push_back(l1);
    l2_true.push_back(l2);
    double l2_rec = std::fmod(l2, 360.0);
    if (l2_rec > 180.0) l2_rec -= 360.0;
    text += FormatDouble(k * 0.01) + "," + FormatDouble(std::fmod(l1, 360.0)) + "," +
            FormatDouble(l2_rec) + ",1500,1500,1500\n";
  }
  WriteText("run.csv", text);
  RunWarnings warnings;
  const RunData data = LoadRunData(Describe("run.csv"), &warnings);
  ASSERT_EQ(data.size(), 100u);
  for (std::size_t k = 0; k < 100; ++k) {
    EXPECT_NEAR(data.lambda_rad[0][k], l1_true[k] * kDegToRad, 1e-12) << k;
    EXPECT_NEAR(data.lambda_rad[1][k], l2_true[k] * kDegToRad, 1e-12) << k;
  }
}

TEST_F(RunIoTest, CsvErrorsNameFileLineAndColumn) {
  const std::string f = Path("run.csv");
  {
    std::vector<std::string> lines = GoodCsv(20);
    for (std::string& l : lines) l = l.substr(0, l.rfind(','));  // drop the last field
    lines.insert(lines.begin(), "# no wz");
    EXPECT_EQ(CsvError(lines), f + ":2: missing column 'wz' (header: t, lambda1, lambda2, wx, wy)");
  }
  {
    std::vector<std::string> lines = GoodCsv(20);
    lines[6] = "0.05,50,5,1515,NaN,1605";
    EXPECT_EQ(CsvError(lines), f + ":7: column 'wy': NaN (every sample must be a number)");
    lines[6] = "0.05,50,5,1515,1390,1605";
    lines[8] = "0.07,70,15,1521,1386,-inf";
    EXPECT_EQ(CsvError(lines),
              f + ":9: column 'wz': infinite value (every sample must be a number)");
  }
  {
    std::vector<std::string> lines = GoodCsv(20);
    lines[4] = "0.03,30,-5,abc,1394,1603";
    EXPECT_EQ(CsvError(lines), f + ":5: column 'wx': not a number: 'abc'");
    lines[4] = "0.03,30,-5,,1394,1603";
    EXPECT_EQ(CsvError(lines), f + ":5: column 'wx': not a number: ''");
    lines[4] = "0.03,30,-5";
    EXPECT_EQ(CsvError(lines), f + ":5: 3 fields, but column 'wx' is field 4 of the header");
  }
  {
    std::vector<std::string> lines = GoodCsv(20);
    lines[8] = "0.05,70,15,1521,1386,1600";
    EXPECT_EQ(CsvError(lines), f + ":9: column 't': time decreases from 0.06 s to 0.05 s");
  }
  EXPECT_EQ(CsvError(GoodCsv(5)), f + ": only 5 samples (at least 10 needed)");
  {
    std::vector<std::string> lines = GoodCsv(12);
    for (int k : {3, 4, 5}) lines[k] = lines[2];
    EXPECT_EQ(CsvError(lines), f + ": only 9 distinct time stamps (at least 10 needed)");
  }
  EXPECT_EQ(CsvError({"# only a comment"}), f + ": no header line (the file is empty)");
  {
    std::vector<std::string> lines = GoodCsv(20);
    lines[0] += ",lambda1_rate";
    for (std::size_t k = 1; k < lines.size(); ++k) lines[k] += ",1";
    EXPECT_EQ(CsvError(lines),
              f + ": column 'lambda1_rate' without the other rate channel (give lambda1_rate "
                  "and lambda2_rate, or neither)");
  }
}

TEST_F(RunIoTest, ReadingsInVoltsAreRejected) {
  std::vector<std::string> lines = GoodCsv(20);
  for (int k = 0; k < 20; ++k) {
    lines[k + 1] = FormatDouble(k / 100.0) + "," + std::to_string(10 * k) + ",0," +
                   FormatDouble(1.5 + 0.003 * k) + ",1400,1600";
  }
  EXPECT_EQ(CsvError(lines), Path("run.csv") +
                                 ": column 'wx': every |value| is below 33.48 mV (2% of the "
                                 "nominal scale + |bias|): looks like V or g, not mV; set "
                                 "columns.wx.unit");
  // Declared as volts, the same file loads.
  RunDescription run = DescribeYaml("data: run.csv\ncolumns: {wx: {source: wx, unit: V}}\n");
  RunWarnings warnings;
  const RunData data = LoadRunData(run, &warnings);
  EXPECT_EQ(data.w_mV[0][1], 1503.0);
  // Declared in mg (a channel that hardly sees gravity), small values are fine.
  run = DescribeYaml("data: run.csv\ncolumns: {wx: {source: wx, unit: mg}}\n");
  EXPECT_EQ(LoadRunData(run, &warnings).w_mV[0][1], 1.503);
}

TEST_F(RunIoTest, AnglesInRadiansAreRejected) {
  std::vector<std::string> lines = GoodCsv(20);
  for (int k = 0; k < 20; ++k) {
    lines[k + 1] = FormatDouble(k / 100.0) + "," + FormatDouble(0.1 * k) + "," +
                   FormatDouble(0.05 * k) + "," + std::to_string(1500 + 10 * k) + ",1400,1600";
  }
  EXPECT_EQ(CsvError(lines), Path("run.csv") +
                                 ": column 'lambda1', column 'lambda2': spans of only 1.9 and "
                                 "0.95 deg while wx swings by 1.092 g: the angles look like "
                                 "radians, not degrees; set columns.lambda1.unit and "
                                 "columns.lambda2.unit to rad");
  RunDescription run = DescribeYaml(
      "data: run.csv\ncolumns: {lambda1: {source: lambda1, unit: rad},\n"
      "          lambda2: {source: lambda2, unit: rad}}\n");
  RunWarnings warnings;
  const RunData data = LoadRunData(run, &warnings);
  EXPECT_NEAR(data.lambda_rad[0][10], 1.0, 1e-15);
}

TEST_F(RunIoTest, MissingDataFile) {
  EXPECT_EQ(ErrorOf(Describe("none.csv")),
            Path("run.yaml") + ": data: no such file '" + Path("none.csv") + "'");
  RunDescription run = DescribeYaml("data: sub/none.mat\n");
  EXPECT_EQ(ErrorOf(run), Path("run.yaml") + ": data: no such file '" + Path("sub/none.mat") + "'");
}

TEST_F(RunIoTest, WarningsCountDuplicatesGapsAndSaturation) {
  std::string text = "t,lambda1,lambda2,wx,wy,wz\n";
  int rows = 0;
  for (int k = 0; k < 2000; ++k) {
    if ((k >= 500 && k < 502) || (k >= 1000 && k < 1004)) continue;         // gaps 0.03 s, 0.05 s
    const double wx = (k >= 1200 && k < 1220) ? 1700.0 : 1500.0 + 0.1 * k;  // clipped
    text += FormatDouble(k / 100.0) + "," + FormatDouble(0.5 * k) + ",0," + FormatDouble(wx) + "," +
            FormatDouble(1400.0 - 0.1 * k) + "," + FormatDouble(1600.0 + std::sin(k)) + "\n";
    ++rows;
    if (k == 100 || k == 200 || k == 300) {  // a repeated stamp with other values
      text += FormatDouble(k / 100.0) + ",0,0,0,0,0\n";
    }
  }
  ASSERT_EQ(rows, 1994);
  WriteText("run.csv", text);
  RunWarnings warnings;
  const RunData data = LoadRunData(Describe("run.csv"), &warnings);
  ASSERT_EQ(data.size(), 1994u);
  EXPECT_EQ(data.w_mV[0][101], 1500.0 + 0.1 * 101);  // the first of the repeated stamps kept
  ASSERT_EQ(warnings.lines.size(), 4u);
  EXPECT_EQ(warnings.lines[0],
            "3 samples with a repeated time stamp dropped (kept the first of "
            "each)");
  EXPECT_EQ(warnings.lines[2],
            "column 'lambda2' is constant (0 deg) in every sample: no motion about the inner "
            "axis (a single-axis rig declares it with {value: ...})");
  EXPECT_EQ(warnings.lines[1],
            "2 gaps in time (intervals > 1.5x the median interval 0.01 s); "
            "the largest is 0.05 s, after t = 9.99 s");
  EXPECT_EQ(warnings.lines[3],
            "column 'wx' may be saturated or clipped: 20 samples (1.003%) at "
            "its maximum 1700 mV in runs of 3 or more");
}

TEST_F(RunIoTest, ReflectionMountingIsAnError) {
  // A left-handed mounting would turn the triad's frame inside out (Kz of
  // 84 695 mV/g was fitted to one): the mounting must be a rotation.
  try {
    DescribeYaml("data: run.csv\nmounting: {axes: [\"+x\", \"+y\", \"-z\"]}\n");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              Path("run.yaml") +
                  ": mounting.axes: [+x, +y, -z] is a reflection (determinant -1), not a "
                  "rotation: flip the sign of one axis (e.g. [+x, +y, +z])");
  }
}

// Writes a MATLAB file (v5 or v7.3) with these variables (each 1 x n or n x 1).
class MatWriter {
 public:
  MatWriter(const std::string& path, mat_ft version)
      : mat_(Mat_CreateVer(path.c_str(), nullptr, version)) {}
  ~MatWriter() {
    if (mat_) Mat_Close(mat_);
  }
  bool ok() const { return mat_ != nullptr; }
  template <typename T>
  void Add(const char* name, std::vector<T> values, bool row, matio_classes cls, matio_types type) {
    std::size_t dims[2] = {values.size(), 1};
    if (row) std::swap(dims[0], dims[1]);
    matvar_t* v = Mat_VarCreate(name, cls, type, 2, dims, values.data(), 0);
    ASSERT_NE(v, nullptr);
    ASSERT_EQ(Mat_VarWrite(mat_, v, MAT_COMPRESSION_NONE), 0);
    Mat_VarFree(v);
  }
  void AddText(const char* name, std::string text) {
    std::size_t dims[2] = {1, text.size()};
    matvar_t* v = Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UINT8, 2, dims, text.data(), 0);
    ASSERT_NE(v, nullptr);
    ASSERT_EQ(Mat_VarWrite(mat_, v, MAT_COMPRESSION_NONE), 0);
    Mat_VarFree(v);
  }

 private:
  mat_t* mat_;
};

TEST_F(RunIoTest, MatFileWithColumnMappingAndMounting) {
  const int n = 200;
  std::vector<double> time(n), enc(n), bad(n);
  std::vector<float> ax(n), ay(n), az(n);
  for (int k = 0; k < n; ++k) {
    time[k] = 10.0 + 0.01 * k;
    enc[k] = 0.9 * k + 2.0;
    ax[k] = 0.05f + 0.001f * static_cast<float>(k % 13);
    ay[k] = static_cast<float>(std::cos(0.9 * k * kDegToRad));
    az[k] = static_cast<float>(-std::sin(0.9 * k * kDegToRad));
    bad[k] = k == 4 ? std::nan("") : 1.0;
  }
  const std::string columns =
      "columns:\n"
      "  t: time\n"
      "  lambda1: {source: enc, offset: -2}\n"
      "  lambda2: {value: 0}\n"
      "  wx: {source: ax, unit: g}\n"
      "  wz: {source: az, unit: g}\n";
  const std::string yaml = "data: rec.mat\nmounting: {axes: [\"+y\", \"+x\", \"-z\"]}\n" + columns +
                           "  wy: {source: ay, unit: g}\n";
  for (mat_ft version : {MAT_FT_MAT73, MAT_FT_MAT5}) {  // v5 stays for the error checks
    SCOPED_TRACE(version == MAT_FT_MAT5 ? "MATLAB v5" : "MATLAB v7.3");
    fs::remove(Path("rec.mat"));
    {
      MatWriter w(Path("rec.mat"), version);
      ASSERT_TRUE(w.ok());
      w.Add("time", time, true, MAT_C_DOUBLE, MAT_T_DOUBLE);  // a row vector
      w.Add("enc", enc, false, MAT_C_DOUBLE, MAT_T_DOUBLE);
      w.Add("ax", ax, false, MAT_C_SINGLE, MAT_T_SINGLE);
      w.Add("ay", ay, false, MAT_C_SINGLE, MAT_T_SINGLE);
      w.Add("az", az, false, MAT_C_SINGLE, MAT_T_SINGLE);
      w.AddText("label", "roll run");
      w.Add("short", std::vector<double>(n - 1, 1.0), false, MAT_C_DOUBLE, MAT_T_DOUBLE);
      w.Add("bad", bad, false, MAT_C_DOUBLE, MAT_T_DOUBLE);
    }
    RunWarnings warnings;
    const RunData data = LoadRunData(DescribeYaml(yaml), &warnings);
    EXPECT_TRUE(warnings.lines.empty());
    ASSERT_EQ(data.size(), static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) {
      ASSERT_EQ(data.t_s[k], time[k]);
      ASSERT_NEAR(data.lambda_rad[0][k], 0.9 * k * kDegToRad, 1e-14);
      ASSERT_EQ(data.lambda_rad[1][k], 0.0);
      ASSERT_EQ(data.w_mV[0][k], 1000.0 * ay[k]);   // platform x = +IMU y
      ASSERT_EQ(data.w_mV[1][k], 1000.0 * ax[k]);   // platform y = +IMU x
      ASSERT_EQ(data.w_mV[2][k], -1000.0 * az[k]);  // platform z = -IMU z
    }
  }

  const std::string f = Path("rec.mat");
  EXPECT_EQ(ErrorOf(DescribeYaml(yaml + "  temp_C: label\n")),
            f + ": variable 'label': not numeric (class char)");
  EXPECT_EQ(ErrorOf(DescribeYaml(yaml + "  temp_C: short\n")),
            f + ": variable 'short': 199 samples, but 'time' has 200");
  EXPECT_EQ(ErrorOf(DescribeYaml(yaml + "  temp_C: tmp\n")),
            f + ": variable 'tmp' (for temp_C) not found (the file has: time, enc, ax, ay, az, "
                "label, short, bad)");
  EXPECT_EQ(ErrorOf(DescribeYaml("data: rec.mat\n" + columns + "  wy: bad\n")),
            f + ": sample 5: variable 'bad' (wy): NaN (every sample must be a number)");
}

// The real single-axis runs (docs/real-data.md): skipped without the shared folder.
class RunIoRealData : public ::testing::TestWithParam<const char*> {};

TEST_P(RunIoRealData, LoadsThroughTheExampleYaml) {
  const std::string name = GetParam();
  const std::string yaml =
      std::string(TRIADCAL_SOURCE_DIR) + "/examples/single-axis-roll/" + name + ".yaml";
  const std::string mat =
      ResolveDataPath(yaml, "shared:data/real/single-axis-encoder/raw_roll_" + name + ".mat");
  if (mat.empty() || !fs::exists(mat)) GTEST_SKIP() << "shared data folder absent";

  const RunDescription run = LoadRunDescription(yaml);
  EXPECT_EQ(run.data_path, mat);
  RunWarnings warnings;
  const auto start = std::chrono::steady_clock::now();
  const RunData data = LoadRunData(run, &warnings);
  const double load_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double duration_s = data.t_s.back() - data.t_s.front();
  std::printf("%s: %zu samples over %.1f s (loaded in %.3f s)\n", name.c_str(), data.size(),
              duration_s, load_s);
  for (const std::string& w : warnings.lines) std::printf("  warning: %s\n", w.c_str());

  // From the files themselves: 149916 / 149788 / 140581 rows with 179 / 211 /
  // 240 repeated stamps, about 1400-1500 s at 100 Hz.
  const std::size_t rows = name == "slow" ? 149916 : name == "medium" ? 149788 : 140581;
  const std::size_t dups = name == "slow" ? 179 : name == "medium" ? 211 : 240;
  EXPECT_EQ(data.size(), rows - dups);
  EXPECT_GT(duration_s, 1400.0);
  EXPECT_LT(duration_s, 1510.0);
  ASSERT_GE(warnings.lines.size(), 2u);
  EXPECT_EQ(warnings.lines[0], std::to_string(dups) +
                                   " samples with a repeated time stamp dropped (kept the "
                                   "first of each)");
  EXPECT_EQ(warnings.lines[1].find("gaps in time (intervals > 1.5x the median interval 0.01 s)"),
            warnings.lines[1].find(' ') + 1);
  EXPECT_FALSE(data.has_rates());
  for (double l2 : data.lambda_rad[1]) ASSERT_EQ(l2, 0.0);

  // The mounting: platform x and z should read (cos l1, sin l1) g up to the
  // chip's scale and bias. Fit w = a cos l1 + b sin l1 + c for each axis.
  const std::size_t n = data.size();
  Eigen::MatrixXd A(n, 3);
  Eigen::MatrixXd W(n, 3);
  for (std::size_t k = 0; k < n; ++k) {
    const double l1 = data.lambda_rad[0][k];
    A.row(k) << std::cos(l1), std::sin(l1), 1.0;
    for (int i = 0; i < 3; ++i) W(k, i) = data.w_mV[i][k] / 1000.0;
  }
  const Eigen::MatrixXd coef = A.colPivHouseholderQr().solve(W);  // 3 x 3: [a; b; c] per axis
  const Eigen::MatrixXd resid = A * coef - W;
  for (int i = 0; i < 3; ++i) {
    std::printf("  platform %c = %+.4f cos l1 %+.4f sin l1 %+.4f g, rms %.1f mg\n", "xyz"[i],
                coef(0, i), coef(1, i), coef(2, i),
                1000.0 * std::sqrt(resid.col(i).squaredNorm() / n));
  }
  // x ~ +cos l1 and z ~ +sin l1: the right axes and signs, and the encoder
  // offset leaves less than 0.5 deg of phase.
  const double phase_x_deg = std::atan2(coef(1, 0), coef(0, 0)) / kDegToRad;
  const double phase_z_deg = std::atan2(-coef(0, 2), coef(1, 2)) / kDegToRad;
  std::printf("  phase: x %.2f deg, z %.2f deg\n", phase_x_deg, phase_z_deg);
  EXPECT_NEAR(coef(0, 0), 1.0, 0.05);
  EXPECT_NEAR(coef(1, 2), 1.0, 0.05);
  EXPECT_LT(std::abs(phase_x_deg), 0.5);
  EXPECT_LT(std::abs(phase_z_deg), 0.5);
  // The shaft axis (platform y) hardly sees gravity.
  EXPECT_LT(std::hypot(coef(0, 1), coef(1, 1)), 0.05);
}

INSTANTIATE_TEST_SUITE_P(RunIo, RunIoRealData, ::testing::Values("slow", "medium", "fast"),
                         [](const ::testing::TestParamInfo<const char*>& p) {
                           return std::string(p.param);
                         });

// The load time of a 40-minute 1 kHz run (2.4 M rows). Run it with
// --gtest_also_run_disabled_tests --gtest_filter='*LargeCsvLoadTime*'.
TEST_F(RunIoTest, DISABLED_LargeCsvLoadTime) {
  const RunData run = MakeRun(2400000, false, false);
  auto start = std::chrono::steady_clock::now();
  WriteRunCsv(run, Path("big.csv"), "2.4 M rows");
  const double write_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  start = std::chrono::steady_clock::now();
  RunWarnings warnings;
  const RunData back = LoadRunData(Describe("big.csv"), &warnings);
  const double load_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("2.4 M rows, %.0f MB: written in %.2f s, loaded in %.2f s\n",
              static_cast<double>(fs::file_size(Path("big.csv"))) / 1e6, write_s, load_s);
  ExpectSameRun(run, back);
}

}  // namespace
}  // namespace triadcal

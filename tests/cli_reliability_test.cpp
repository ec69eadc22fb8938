// Reliability, round 2 (issue 34): no crash, no hang, no silent acceptance.
// Each case of the adversarial corpus runs through the built `triadcal`: bad
// input gives exit 2, exactly one line on stderr naming the file, key or
// option, and no output written or changed; plausible but suspicious input a
// warning that names it. The cases with device nodes need root (mknod) and
// skip otherwise.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <matio.h>
#include <zlib.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/model/parameters.h"
#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "tests/sim_fixtures.h"
#include "tests/cli_test.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::CliResult;

// The 21 sensor parameters of a calibration file, Kx..Kzz, with units;
// `extra` is spliced into the parameters object.
std::string CalibrationJson(const std::string& kx = "{\"value\": 174, \"unit\": \"mV/g\"}",
                            const std::string& scale_unit = "mV/g", const std::string& extra = "",
                            double scale = 174.0) {
  char k[64];
  std::snprintf(k, sizeof(k), "%.17g", scale);
  std::string p = "{\"command\": \"fit\", \"parameters\": {\"Kx\": " + kx;
  for (const char* s : {"Ky", "Kz"}) {
    p += std::string(", \"") + s + "\": {\"value\": " + k + ", \"unit\": \"" + scale_unit + "\"}";
  }
  const std::string bias_unit = scale_unit.substr(0, scale_unit.find('/'));
  for (const char* b : {"W0x", "W0y", "W0z"}) {
    p += std::string(", \"") + b + "\": {\"value\": 1500, \"unit\": \"" + bias_unit + "\"}";
  }
  for (const char* a : {"alpha_x", "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z"}) {
    p += std::string(", \"") + a + "\": {\"value\": 0, \"unit\": \"arcmin\"}";
  }
  for (const char* n : {"Kxx", "Kxy", "Kxz", "Kyx", "Kyy", "Kyz", "Kzx", "Kzy", "Kzz"}) {
    p += std::string(", \"") + n + "\": {\"value\": 0, \"unit\": \"1/g\"}";
  }
  return p + extra + "}}";
}

class CliReliability : public testing_fixtures::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    WriteText("cal.json", CalibrationJson());
  }

  std::string Fit(const std::string& options) const {
    return "fit " + Path("run.yaml") + " -o " + Path("out.json") + " " + options;
  }
  std::string Apply(const std::string& cal, const std::string& out) const {
    return "apply " + cal + " " + Path("run.yaml") + " -o " + out;
  }

  static bool IsRoot() { return ::geteuid() == 0; }
  static bool IsCharDevice(const std::string& p) {
    struct stat st {};
    return ::lstat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
  }
  static bool IsFifo(const std::string& p) {
    struct stat st {};
    return ::lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
  }
};

// ---- options: validated where parsed, the range in --help, one line naming the flag

TEST_F(CliReliability, RateWindowOutOfRange) {
  // 0 and NaN crashed (segmentation fault), 1e6 s ran past 120 s.
  for (const char* v : {"0", "nan", "1e6", "-0.1", "inf"}) {
    ExpectError(Fit(std::string("--rate-window-s ") + v),
                std::string("--rate-window-s: Value ") + v +
                    " not in range 0.001000 to 2.000000 (see `triadcal fit --help`)");
  }
  ExpectError("filter " + Path("run.yaml") + " -o " + Path("out.json") + " --rate-window-s nan",
              "--rate-window-s: Value nan not in range 0.001000 to 2.000000 (see `triadcal filter --help`)");
  ExpectError("static " + Path("run.yaml") + " -o " + Path("out.json") + " --rate-window-s 0",
              "--rate-window-s: Value 0 not in range 0.001000 to 2.000000 (see `triadcal static --help`)");
  ExpectError(
      "observability " + Path("run.yaml") + " -o " + Path("out.json") + " --rate-window-s 1e6",
      "--rate-window-s: Value 1e6 not in range 0.001000 to 2.000000 (see `triadcal observability "
      "--help`)");
}

TEST_F(CliReliability, HelpShowsTheRanges) {
  const std::string help = Path("help.txt");
  ASSERT_EQ(std::system((std::string(TRIADCAL_BIN) + " fit --help > " + help).c_str()), 0);
  const std::string text = ReadFile(help);
  EXPECT_NE(text.find("in [0.001, 2]"), std::string::npos) << text;   // --rate-window-s
  EXPECT_NE(text.find("in [0.01, 10]"), std::string::npos) << text;   // --epoch-s
  EXPECT_NE(text.find("INT:in [0, 1024]"), std::string::npos) << text;  // --threads
}

TEST_F(CliReliability, IterationsAndThreadsAreBounded) {
  ExpectError("filter " + Path("run.yaml") + " -o " + Path("out.json") + " --iterations 1e9",
              "--iterations: Value 1e9 not in range 1 to 20 (see `triadcal filter --help`)");
  ExpectError("filter " + Path("run.yaml") + " -o " + Path("out.json") + " --iterations 0",
              "--iterations: Value 0 not in range 1 to 20 (see `triadcal filter --help`)");
  ExpectError(Fit("--threads -1"),
              "--threads: Value -1 not in range 0 to 1024 (see `triadcal fit --help`)");
  ExpectError(Fit("--threads nan"),
              "--threads: Value nan not in range 0 to 1024 (see `triadcal fit --help`)");
}

TEST_F(CliReliability, SeedsThatWrapOrSaturate) {
  const std::string sc = WriteText("sc.yaml", "profile: {duration_s: 2, rate_hz: 20}\n");
  ExpectError("simulate " + sc + " -o " + Path("sim") + " --seed -1",
              "--seed: expected an integer 0 to 18446744073709551615, got '-1'", {"sim"});
  ExpectError("simulate " + sc + " -o " + Path("sim") + " --seed 18446744073709551616",
              "--seed: expected an integer 0 to 18446744073709551615, got "
              "'18446744073709551616'",
              {"sim"});
  ExpectError("simulate " + sc + " -o " + Path("sim") + " --seed 1e3",
              "--seed: expected an integer 0 to 18446744073709551615, got '1e3'", {"sim"});
  const CliResult ok =
      Run("simulate " + sc + " -o " + Path("sim") + " --seed 18446744073709551615");
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  ExpectError("montecarlo " + sc + " -o " + Path("out.json") + " --first-seed -1 -n 2",
              "--first-seed: expected an integer 0 to 18446744073709551615, got '-1'");
  ExpectError(
      "montecarlo " + sc + " -o " + Path("out.json") + " --first-seed 18446744073709551615 -n 2",
      "--first-seed: 2 runs from seed 18446744073709551615 pass the largest seed "
      "18446744073709551615 (2^64 - 1): at most 1 from there");
}

TEST_F(CliReliability, HoldAndFreeTogetherOrEverythingHeld) {
  ExpectError(Fit("--hold dpsi,Kxy --free Kxy"),
              "--hold/--free: 'Kxy' given to both: hold it or free it");
  ExpectError("filter " + Path("run.yaml") + " -o " + Path("out.json") + " --hold Kx --free Kx",
              "--hold/--free: 'Kx' given to both: hold it or free it");
  std::string all;
  const ParameterLayout layout;
  for (int i = 0; i < layout.size(); ++i) all += (i ? "," : "") + layout.info(i).name;
  ExpectError(Fit("--hold " + all), "--hold: holds every parameter; nothing left to estimate");
}

TEST_F(CliReliability, EmptyOutputName) {
  ExpectError("fit " + Path("run.yaml") + " -o ''", "-o: empty file name (give a file name)", {});
  ExpectError(Apply(Path("cal.json"), "''"), "-o: empty file name (give a file name)", {});
  ExpectError(
      "simulate " + WriteText("sc.yaml", "profile: {duration_s: 2, rate_hz: 20}\n") + " -o ''",
      "-o: empty folder name (give a folder)", {});
}

// ---- outputs: regular files only, never an input, temporaries cleaned

TEST_F(CliReliability, OutputsThatAreNotRegularFiles) {
  // A folder, a FIFO nobody reads (it hung), a symbolic link to a FIFO; all
  // refused before any work, --force or not, and left as they were.
  fs::create_directories(Path("dir.csv"));
  ExpectError(Apply(Path("cal.json"), Path("dir.csv")) + " --force",
              Path("dir.csv") + ": cannot write: is a directory", {});
  ASSERT_EQ(::mkfifo(Path("fifo.csv").c_str(), 0644), 0);
  ExpectError(Apply(Path("cal.json"), Path("fifo.csv")) + " --force",
              Path("fifo.csv") +
                  ": cannot write: is a FIFO (named pipe), not a regular file; outputs are "
                  "written whole, as regular files",
              {});
  EXPECT_TRUE(IsFifo(Path("fifo.csv")));
  fs::create_symlink(Path("fifo.csv"), Path("link.json"));
  ExpectError("export " + Path("cal.json") + " --format json-matrix -o " + Path("link.json"),
              Path("link.json") +
                  ": cannot write: is a symbolic link to a FIFO (named pipe), not a regular "
                  "file; outputs are regular files",
              {});
  EXPECT_TRUE(IsFifo(Path("fifo.csv")));
  EXPECT_TRUE(fs::is_symlink(Path("link.json")));
  fs::create_symlink(Path("missing.csv"), Path("dangling.csv"));
  ExpectError(Apply(Path("cal.json"), Path("dangling.csv")),
              Path("dangling.csv") +
                  ": cannot write: is a symbolic link to a missing file; outputs are regular files",
              {});
}

TEST_F(CliReliability, DeviceNodesAreNeverReplaced) {
  if (!IsRoot()) GTEST_SKIP() << "mknod needs root";
  // Copies of /dev/null and /dev/zero: -o onto /dev/null --force replaced it
  // with a regular file, onto /dev/zero the guard read 4 GB.
  ASSERT_EQ(::mknod(Path("null").c_str(), S_IFCHR | 0666, makedev(1, 3)), 0);
  ASSERT_EQ(::mknod(Path("zero").c_str(), S_IFCHR | 0666, makedev(1, 5)), 0);
  for (const char* dev : {"null", "zero"}) {
    ExpectError(Apply(Path("cal.json"), Path(dev)) + " --force",
                Path(dev) +
                    ": cannot write: is a device node, not a regular file; outputs are written "
                    "whole, as regular files",
                {});
    ExpectError("fit " + Path("run.yaml") + " --force -o " + Path(dev),
                Path(dev) +
                    ": cannot write: is a device node, not a regular file; outputs are written "
                    "whole, as regular files",
                {});
    EXPECT_TRUE(IsCharDevice(Path(dev))) << dev;
  }
  // The stdout of the process: /dev/null here, a pipe under `| cat` (it hung).
  ExpectError(Apply(Path("cal.json"), "/dev/stdout"),
              "/dev/stdout: cannot write: is a symbolic link to a device node, not a regular "
              "file; outputs are regular files",
              {});
}

TEST_F(CliReliability, StdoutPipeIsNotWaitedOn) {
  const std::string err = Path("err.txt");
  const int status =
      std::system((std::string(TRIADCAL_BIN) + " " + Apply(Path("cal.json"), "/dev/stdout") +
                   " 2> " + err + " | cat > /dev/null")
                      .c_str());
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(ReadFile(err),
            "triadcal: error: /dev/stdout: cannot write: is a symbolic link to a FIFO (named "
            "pipe), not a regular file; outputs are regular files\n");
}

TEST_F(CliReliability, SymlinkToARegularFileIsWrittenThrough) {
  WriteText("target.csv", "old\n");
  fs::create_symlink(Path("target.csv"), Path("link.csv"));
  const CliResult r = Run(Apply(Path("cal.json"), Path("link.csv")) + " --force");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(Path("link.csv")));
  EXPECT_EQ(ReadFile(Path("target.csv")).rfind("# triadcal apply: calibration ", 0), 0u);
}

TEST_F(CliReliability, DashWritesToStdout) {
  // Where a text output makes sense on stdout: apply's CSV, export's YAML.
  const std::string out = Path("stdout.txt"), err = Path("err.txt");
  ASSERT_EQ(std::system((std::string(TRIADCAL_BIN) + " " + Apply(Path("cal.json"), "-") + " > " +
                         out + " 2> " + err)
                            .c_str()),
            0)
      << ReadFile(err);
  EXPECT_EQ(ReadFile(out).rfind("# triadcal apply: calibration ", 0), 0u);
  EXPECT_EQ(ReadFile(err), "");
  EXPECT_FALSE(fs::exists(Path("-")));
  ASSERT_EQ(std::system((std::string(TRIADCAL_BIN) + " export " + Path("cal.json") +
                         " --format yaml -o - > " + out + " 2> " + err)
                            .c_str()),
            0)
      << ReadFile(err);
  EXPECT_EQ(ReadFile(out).rfind("# triadcal calibration, plain matrix form", 0), 0u);
  ExpectError("export " + Path("cal.json") + " --format c -o -",
              "-o -: --format c writes two files (NAME.c and NAME.h), not stdout", {"-"});
  ExpectError("fit " + Path("run.yaml") + " -o -",
              "-o -: this command prints its summary on stdout; give a file name (stdout takes "
              "the output of apply and export)",
              {"-"});
}

TEST_F(CliReliability, SimulateNeverOverwritesItsScenarioEvenWithForce) {
  // The scenario is named run.yaml and the output folder is its own: DIR/run.yaml
  // would replace it.
  fs::create_directories(Path("here"));
  const std::string scenario =
      "profile: {duration_s: 2, rate_hz: 20}\nrun: {triad: {noise_mV: 2}}\n";
  const std::string sc = (dir_ / "here" / "run.yaml").string();
  std::ofstream(sc) << scenario;
  for (const char* force : {"", " --force"}) {
    ExpectError("simulate " + sc + " -o " + Path("here") + force,
                (dir_ / "here" / "run.yaml").string() + ": is the input file '" + sc +
                    "' (an output never replaces an input; choose another name)",
                {"here/run.csv", "here/truth.json"});
    EXPECT_EQ(ReadFile(sc), scenario);
  }
  // With a relative -o ".", from the folder.
  const CliResult r = Run("simulate run.yaml -o . --force", "cd " + Path("here") + " &&");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err,
            "triadcal: error: ./run.yaml: is the input file 'run.yaml' (an output never "
            "replaces an input; choose another name)\n");
  EXPECT_EQ(ReadFile(sc), scenario);
}

TEST_F(CliReliability, SimulateRefusesAFifoInItsFolder) {
  fs::create_directories(Path("sim"));
  ASSERT_EQ(::mkfifo(Path("sim/run.csv").c_str(), 0644), 0);
  const std::string sc = WriteText("sc.yaml", "profile: {duration_s: 2, rate_hz: 20}\n");
  ExpectError("simulate " + sc + " -o " + Path("sim") + " --force",
              Path("sim") +
                  "/run.csv: cannot write: is a FIFO (named pipe), not a regular file; "
                  "outputs are written whole, as regular files",
              {"sim/run.yaml", "sim/truth.json"});
  EXPECT_TRUE(IsFifo(Path("sim/run.csv")));
}

TEST_F(CliReliability, StaleTemporariesAreRemovedOnTheNextRun) {
  // A process that is gone: a child that exited.
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);
  const std::string dead = std::to_string(child), live = std::to_string(::getpid());
  const std::string host = HostTag();
  const std::vector<std::string> stale = {".tmp.out.csv." + host + "." + dead,
                                          ".tmp.out.csv." + dead};  // earlier versions
  const std::vector<std::string> kept = {
      ".tmp.out.csv." + host + "." + live,         // a running process
      ".tmp.out.csv.otherhost." + dead,            // another host's: it may be running
      ".tmp.other.csv." + host + "." + dead,       // another output's
      ".tmp.out.csv." + host + "." + dead + "x"};  // not a temporary of ours
  for (const std::string& f : stale) WriteText(f, "partial");
  for (const std::string& f : kept) WriteText(f, "partial");
  const CliResult r = Run(Apply(Path("cal.json"), Path("out.csv")));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  for (const std::string& f : stale) EXPECT_FALSE(fs::exists(Path(f))) << f;
  for (const std::string& f : kept) EXPECT_TRUE(fs::exists(Path(f))) << f;
  // Nothing of its own left beside the output.
  int temporaries = 0;
  for (const auto& e : fs::directory_iterator(dir_)) {
    temporaries += e.path().filename().string().rfind(".tmp.out.csv.", 0) == 0;
  }
  EXPECT_EQ(temporaries, 3);  // the three kept ones that name out.csv
}

TEST_F(CliReliability, GuardReadsOnlyTheHeadOfAnExistingOutput) {
  // A 40-MB regular file of one line (no provenance): refused without --force,
  // replaced with it. The guard reads 1 MB of its start and of its end.
  {
    std::ofstream big(Path("big.json"), std::ios::binary);
    big << '{';
    const std::string chunk(1 << 20, 'x');
    for (int i = 0; i < 40; ++i) big << chunk;
  }
  ExpectError("export " + Path("cal.json") + " --format json-matrix -o " + Path("big.json"),
              Path("big.json") +
                  ": exists and is not a triadcal output (no provenance); --force overwrites it",
              {});
  // A JSON output of this version carries its provenance first: found in the
  // head however long the rest.
  const CliResult first =
      Run("export " + Path("cal.json") + " --format json-matrix -o " + Path("m.json"));
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_EQ(ReadFile(Path("m.json")).rfind("{\n  \"provenance\": {", 0), 0u);
  const CliResult again =
      Run("export " + Path("cal.json") + " --format json-matrix -o " + Path("m.json"));
  EXPECT_EQ(again.exit_code, 0) << again.err;
}

// ---- readers: paths, MAT elements, excerpts, YAML documents

TEST_F(CliReliability, DataPathsThatAreNotFiles) {
  const std::string y = Path("bad.yaml");
  fs::create_directories(Path("folder"));
  WriteText("bad.yaml", "data: folder\n");
  ExpectError("fit " + y + " -o " + Path("out.json"),
              y + ": data: cannot read '" + Path("folder") + "': is a directory, not a file");
  ASSERT_EQ(::mkfifo(Path("fifo.csv").c_str(), 0644), 0);
  WriteText("bad.yaml", "data: fifo.csv\n");
  ExpectError("fit " + y + " -o " + Path("out.json"),
              y + ": data: cannot read '" + Path("fifo.csv") +
                  "': is a FIFO (named pipe), not a regular file");
  fs::create_symlink(Path("loop_a.csv"), Path("loop_b.csv"));
  fs::create_symlink(Path("loop_b.csv"), Path("loop_a.csv"));
  WriteText("bad.yaml", "data: loop_a.csv\n");
  ExpectError("fit " + y + " -o " + Path("out.json"),
              y + ": data: cannot read '" + Path("loop_a.csv") +
                  "': too many levels of symbolic links (a symlink loop?)");
  const std::string long_name(300, 'a');
  WriteText("bad.yaml", "data: " + long_name + ".csv\n");
  const CliResult r = Run("fit " + y + " -o " + Path("out.json"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("triadcal: error: " + y + ": data: cannot read '", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("...aaaaaaaa.csv': file name too long (longer than the system allows)\n"),
            std::string::npos)
      << r.err;
  EXPECT_LT(r.err.size(), 400u) << r.err;
  // A run.yaml that is a folder, a FIFO, a loop.
  ExpectError("fit " + Path("folder") + " -o " + Path("out.json"),
              Path("folder") + ": cannot read: is a directory, not a file");
  ExpectError("fit " + Path("loop_a.csv") + " -o " + Path("out.json"),
              Path("loop_a.csv") +
                  ": cannot read: too many levels of symbolic links (a symlink "
                  "loop?)");
  ExpectError("apply " + Path("fifo.csv") + " " + Path("run.yaml") + " -o " + Path("w.csv"),
              Path("fifo.csv") + ": cannot read: is a FIFO (named pipe), not a regular file",
              {"w.csv"});
}

TEST_F(CliReliability, PermissionDeniedIsSaid) {
  if (IsRoot()) GTEST_SKIP() << "root reads every file";
  WriteText("secret.csv", ReadFile(Path("run.csv")));
  ::chmod(Path("secret.csv").c_str(), 0);
  WriteText("bad.yaml", "data: secret.csv\n");
  ExpectError(
      "fit " + Path("bad.yaml") + " -o " + Path("out.json"),
      Path("bad.yaml") + ": data: cannot read '" + Path("secret.csv") + "': permission denied");
}

TEST_F(CliReliability, ErrorsEchoOnlyAnExcerptOfTheInput) {
  // /proc/self/environ as data: one header "line" holding the whole environment.
  WriteText("env.yaml", "data: /proc/self/environ\n");
  const CliResult r = Run("fit " + Path("env.yaml") + " -o " + Path("out.json"),
                          "TRIADCAL_TEST_SECRET=s3cr3t_value_that_must_not_appear");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.find("s3cr3t_value"), std::string::npos) << r.err;
  EXPECT_LT(r.err.size(), 1200u) << r.err;
  // A field of a million characters in a row.
  const std::vector<std::string> lines = [&] {
    std::vector<std::string> out;
    std::ifstream in(Path("run.csv"));
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  }();
  std::string csv = lines[0] + "\n" + std::string(1000000, 'z') + ",0,0,0,0,0\n";
  for (std::size_t i = 2; i < lines.size(); ++i) csv += lines[i] + "\n";
  WriteText("long.csv", csv);
  WriteText("long.yaml", "data: long.csv\n");
  ExpectError("fit " + Path("long.yaml") + " -o " + Path("out.json"),
              Path("long.csv") +
                  ":2: column 't': not a number: 'zzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzzz"
                  "zzzz...zzzzzzzzzzzz'");
}

TEST_F(CliReliability, HugeHeadersAndRowsAreBounded) {
  // 80 000 names took 8 s (a quadratic duplicate check), a million never ended.
  std::string header = "t,lambda1,lambda2,wx,wy,wz";
  for (int i = 0; i < 9000; ++i) header += ",c" + std::to_string(i);
  header += ",c17\n";
  WriteText("dup.csv", header);
  WriteText("dup.yaml", "data: dup.csv\n");
  ExpectError("fit " + Path("dup.yaml") + " -o " + Path("out.json"),
              Path("dup.csv") +
                  ":1: column 'c17' appears twice (fields 24 and 9007); rename one, "
                  "or name the columns with data_format.header");
  std::string wide = "t";
  for (int i = 0; i < 1000000; ++i) wide += ",c" + std::to_string(i);
  WriteText("wide.csv", wide + "\n");
  WriteText("wide.yaml", "data: wide.csv\n");
  ExpectError("fit " + Path("wide.yaml") + " -o " + Path("out.json"),
              Path("wide.csv") +
                  ":1: the header has more than 10000 columns (bound: a run file "
                  "has a few dozen; is this a data file?)");
  // A row of a million fields under a header of six.
  std::string row = "0";
  for (int i = 0; i < 999999; ++i) row += ",1";
  WriteText("row.csv", "t,lambda1,lambda2,wx,wy,wz\n" + row + "\n");
  WriteText("row.yaml", "data: row.csv\n");
  ExpectError("fit " + Path("row.yaml") + " -o " + Path("out.json"),
              Path("row.csv") +
                  ":2: 1000000 fields, but the header (line 1) has 6 (a decimal "
                  "comma?)");
}

// A fuzzer's damaged scenario on which YAML::LoadAll never ended (it found
// "documents" without consuming input): only two documents are ever parsed.
TEST_F(CliReliability, DamagedYamlEnds) {
  const std::string sc = WriteText(
      "sc.yaml",
      ", 90], period_s: [30, 12], phase_deg: [0, 0], duration_s: 90, rate_hprofile: "
      "{amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0], duration_s: 90, "
      "rate_hz: 100}\ntruth: {Kx: 171.5, dpsi: -33, dx2: -7}\nnoise: {cacel_mVse_mzV:  d, "
      "constraints: []}\n");
  const CliResult r = Run("simulate " + sc + " -o " + Path("sim"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("triadcal: error: " + sc + ":", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(CliReliability, SecondYamlDocumentIsAnError) {
  WriteText("two.yaml", "data: run.csv\n---\ntriad: {noise_mV: 3}\n");
  ExpectError("fit " + Path("two.yaml") + " -o " + Path("out.json"),
              Path("two.yaml") +
                  ":3: a second YAML document (after ---); a triadcal file holds "
                  "one (merge them, or remove the ---)");
  // An empty document after a trailing --- holds nothing: fine.
  WriteText("one.yaml", "data: run.csv\n---\n");
  const CliResult r =
      Run("apply " + Path("cal.json") + " " + Path("one.yaml") + " -o " + Path("w.csv"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// MAT v5: a file of the run's six columns, and the offset of the data tag of
// variable `v` (its real part), found by walking the elements.
class MatElements : public CliReliability {
 protected:
  void SetUp() override {
    CliReliability::SetUp();
    const RunData d = Simulate(testing_fixtures::PaperScenario(50.0, 20.0, 2.0, 15.0, 11));
    std::vector<std::vector<double>> cols = {d.t_s,     d.lambda_rad[0], d.lambda_rad[1],
                                             d.w_mV[0], d.w_mV[1],       d.w_mV[2]};
    for (double& x : cols[1]) x /= kDegToRad;
    for (double& x : cols[2]) x /= kDegToRad;
    mat_t* mat = Mat_CreateVer(Path("run.mat").c_str(), nullptr, MAT_FT_MAT5);
    ASSERT_NE(mat, nullptr);
    const char* names[] = {"t", "lambda1", "lambda2", "wx", "wy", "wz"};
    for (int v = 0; v < 6; ++v) {
      std::size_t dims[2] = {cols[v].size(), 1};
      matvar_t* var = Mat_VarCreate(names[v], MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, cols[v].data(),
                                    MAT_F_DONT_COPY_DATA);
      Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE);
      Mat_VarFree(var);
    }
    Mat_Close(mat);
    bytes_ = ReadFile(Path("run.mat"));
    samples_ = d.size();
    WriteText("mat.yaml", "data: bad.mat\n");
  }

  std::uint32_t U32(std::size_t at) const {
    std::uint32_t v;
    std::memcpy(&v, &bytes_[at], 4);
    return v;
  }
  void SetU32(std::string* b, std::size_t at, std::uint32_t v) const {
    std::memcpy(&(*b)[at], &v, 4);
  }
  // Offset of the miMATRIX tag of variable v, and of its real part's tag.
  std::size_t MatrixAt(int v) const {
    std::size_t pos = 128;
    for (int i = 0; i < v; ++i) pos += 8 + U32(pos + 4);
    return pos;
  }
  std::size_t DataTagAt(int v) const {
    std::size_t at = MatrixAt(v) + 8;     // array flags
    at += 16;                             // flags tag and 8 bytes
    at += 8 + (U32(at + 4) + 7) / 8 * 8;  // dimensions
    const std::uint32_t name = U32(at);
    at += (name >> 16) ? 8 : 8 + (U32(at + 4) + 7) / 8 * 8;  // name (small or not)
    return at;
  }
  CliResult FitMat(const std::string& b) {
    WriteText("bad.mat", b);
    return Run("fit " + Path("mat.yaml") + " -o " + Path("out.json"));
  }

  std::string bytes_;
  std::size_t samples_ = 0;
};

TEST_F(MatElements, DataThatOverrunTheirTag) {
  std::string b = bytes_;
  const std::size_t tag = DataTagAt(3);  // wx
  const std::uint32_t declared = U32(tag + 4);
  SetU32(&b, tag + 4, declared + 800);
  const std::size_t matrix_end = MatrixAt(3) + 8 + U32(MatrixAt(3) + 4);
  const CliResult r = FitMat(b);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": damaged MATLAB file (variable 'wx': its data (" +
                       std::to_string(declared + 800) +
                       " bytes) overrun the variable's element, which ends " +
                       std::to_string(matrix_end - tag - 8) + " bytes after their tag)\n");
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

TEST_F(MatElements, DataShorterThanTheDimensions) {
  std::string b = bytes_;
  const std::size_t matrix = MatrixAt(4);  // wy: dims say one sample more than the data hold
  const std::size_t dims_at = matrix + 8 + 16 + 8;
  SetU32(&b, dims_at, static_cast<std::uint32_t>(samples_ + 1));
  const CliResult r = FitMat(b);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": damaged MATLAB file (variable 'wy': its data hold " +
                       std::to_string(samples_) + " values, but its dimensions declare " +
                       std::to_string(samples_ + 1) + "x1 (data cut short?))\n");
}

TEST_F(MatElements, TextWhereDoublesAreDeclared) {
  std::string b = bytes_;
  const std::size_t tag = DataTagAt(5);  // wz: the same bytes, typed miUTF8
  SetU32(&b, tag, 16);
  const CliResult r = FitMat(b);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": damaged MATLAB file (variable 'wz': class double declares numbers, but "
                       "its data are text (miUTF8))\n");
}

// A compressed element that holds no variable (a fuzzer's file): the walk
// does not loop on it (it looped on this one for ever) and names it: a
// top-level compressed element holds one variable (matio said "Uncompressed
// type not MAT_T_MATRIX" in its log, which the reader no longer captures).
TEST_F(MatElements, CompressedElementWithoutAVariableIsRefused) {
  unsigned char inner[16] = {1, 0, 0, 0, 4, 0, 0, 0, 'a', 'b', 'c', 'd', 0, 0, 0, 0};  // miINT8
  uLongf packed_size = compressBound(sizeof(inner));
  std::vector<unsigned char> packed(packed_size);
  ASSERT_EQ(compress(packed.data(), &packed_size, inner, sizeof(inner)), Z_OK);
  std::string element(8, '\0');
  const std::uint32_t tag[2] = {15, static_cast<std::uint32_t>(packed_size)};
  std::memcpy(&element[0], tag, 8);
  element.append(reinterpret_cast<const char*>(packed.data()), packed_size);
  const CliResult r = FitMat(bytes_.substr(0, 128) + element + bytes_.substr(128));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": damaged MATLAB file (element 1: its compressed data hold data type 1, "
                       "not a variable (miMATRIX, 14))\n");
}

// A v7.3 file (HDF5 inside) cut short: HDF5 cannot open it and matio finds no
// variable. One line, and nothing of HDF5's own report of the failure on
// stderr (the command turns it off: SilenceMatioDiagnostics).
TEST_F(MatElements, CutV73FileSaysDamagedOnOneLine) {
  const RunData d = Simulate(testing_fixtures::PaperScenario(50.0, 20.0, 2.0, 15.0, 11));
  mat_t* mat = Mat_CreateVer(Path("v73.mat").c_str(), nullptr, MAT_FT_MAT73);
  ASSERT_NE(mat, nullptr);
  std::vector<double> column = d.t_s;
  std::size_t dims[2] = {column.size(), 1};
  for (const char* name : {"t", "lambda1", "lambda2", "wx", "wy", "wz"}) {
    matvar_t* var = Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, column.data(),
                                  MAT_F_DONT_COPY_DATA);
    Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE);
    Mat_VarFree(var);
  }
  Mat_Close(mat);
  const std::string whole = ReadFile(Path("v73.mat"));
  const CliResult r = FitMat(whole.substr(0, whole.size() * 3 / 4));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": damaged MATLAB file (a v7.3 file in which matio finds no variable: "
                       "HDF5 cannot read it, cut short?)\n");
}

// A cell array whose dimensions say 6e12 elements in a file of a few KB:
// matio allocated what they said before reading (48 TB: a fuzzer's crash).
TEST_F(MatElements, CellDimensionsBeyondTheFile) {
  std::string b = bytes_;
  const std::size_t matrix = MatrixAt(0);  // t
  b[matrix + 16] = 1;                      // class: cell
  SetU32(&b, matrix + 32, 11862028);
  SetU32(&b, matrix + 36, 524289);
  const CliResult r = FitMat(b);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": damaged MATLAB file (variable 't' declares 11862028x524289 values, more "
                       "than the " +
                       std::to_string(b.size()) + "-byte file can hold)\n");
}

// Any class: a sub-element that overruns the variable (a sparse index tag of
// 4 GB in a 560-byte file made matio allocate 4 GB: a fuzzer's case); here
// the data of a character array.
TEST_F(MatElements, PartsOfAnyClassStayInsideTheVariable) {
  std::string b = bytes_;
  const std::size_t matrix = MatrixAt(5);  // wz, made a char array
  b[matrix + 16] = 4;
  const std::size_t tag = DataTagAt(5);
  SetU32(&b, tag + 4, 0xFFFFFFC7u);
  const std::size_t matrix_end = matrix + 8 + U32(matrix + 4);
  const CliResult r = FitMat(b);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": damaged MATLAB file (variable 'wz': a part of 4294967239 bytes overruns "
                       "the variable's element, which ends " +
                       std::to_string(matrix_end - tag - 8) + " bytes after its tag)\n");
}

// Without its 128-byte header matio took the file for MAT v4 and allocated
// what its first bytes said (1.7 GB for a fuzzer's 305 bytes).
TEST_F(MatElements, FileWithoutItsHeaderIsRefused) {
  const CliResult r = FitMat(bytes_.substr(128));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "triadcal: error: " + Path("bad.mat") +
                       ": not a MATLAB v5/v7 file (no 128-byte MAT-file header with its version "
                       "and byte order; MAT v4 files are not read: save with -v7)\n");
}

TEST_F(MatElements, TheUntouchedFileLoads) {
  WriteText("bad.mat", bytes_);
  RunWarnings warnings;
  RunDescription run;
  run.yaml_path = Path("mat.yaml");
  run.data_path = Path("bad.mat");
  EXPECT_EQ(LoadRunData(run, &warnings).size(), samples_);
}

// ---- calibration JSON for apply and export: validated like run.yaml

TEST_F(CliReliability, CalibrationValuesThatNoSensorHas) {
  const std::string c = Path("c.json");
  WriteText("c.json", CalibrationJson("{\"value\": -171.5, \"unit\": \"mV/g\"}"));
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.Kx: -171.5 mV/g: a scale factor must be > 0 (an axis that reads "
                  "-1 g when it points up belongs in the run's mounting.axes)",
              {"w.csv"});
  WriteText("c.json", CalibrationJson("{\"value\": 1e300, \"unit\": \"mV/g\"}"));
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.Kx: 1e+300 mV/g is outside [0.001, 1e+08] per g (no "
                  "accelerometer output is outside this range)",
              {"w.csv"});
  ExpectError("export " + c + " --format yaml -o " + Path("m.yaml"),
              c + ": parameters.Kx: 1e+300 mV/g is outside [0.001, 1e+08] per g (no "
                  "accelerometer output is outside this range)",
              {"m.yaml"});
}

TEST_F(CliReliability, CalibrationInOtherUnitsThanTheRun) {
  const std::string c = Path("c.json");
  // In mg, on a run in mV: every |W| came out 1.3-1.65 g.
  WriteText("c.json", CalibrationJson("{\"value\": 1000, \"unit\": \"mg/g\"}", "mg/g", "", 1000));
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.Kx: the calibration is in mg/g, but the run " + Path("run.yaml") +
                  " reads mV (columns.wx.unit): a calibration applies to readings in its own unit",
              {"w.csv"});
  // 0.1715 "mV/g": a V/g slip (Wx from -1730 to 849 g). With the bias in mV
  // it is 8746 g worth of the scale; with the bias in V too, the scale is
  // 1015 times below the run's.
  WriteText("c.json", CalibrationJson("{\"value\": 0.1715, \"unit\": \"mV/g\"}"));
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.W0x: 1500 is 8746 g worth of Kx = 0.1715 (bound 1000 g): scale "
                  "and bias in different units (V/g for mV/g?)",
              {"w.csv"});
  std::string volts = CalibrationJson("{\"value\": 0.1715, \"unit\": \"mV/g\"}");
  const std::string mv = "\"value\": 1500,";
  for (std::size_t at; (at = volts.find(mv)) != std::string::npos;) {
    volts.replace(at, mv.size(), "\"value\": 1.5,");
  }
  WriteText("c.json", volts);
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.Kx: 0.1715 mV/g is 1015 times below the run's nominal scale 174 "
                  "mV/g (" +
                  Path("run.yaml") +
                  ": triad.scale_mV_per_g; bound: a factor 10): V/g given as mV/g, or the "
                  "calibration of another sensor?",
              {"w.csv"});
  // Units mixed within one calibration.
  WriteText("c.json", CalibrationJson("{\"value\": 174, \"unit\": \"mV/g\"}", "mg/g"));
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.Ky: unit mg/g is in mg, but Kx is in mV: one calibration has one "
                  "readings unit",
              {"w.csv"});
}

TEST_F(CliReliability, CalibrationKeysOfAnotherBuildOrGivenTwice) {
  const std::string c = Path("c.json");
  WriteText("c.json", CalibrationJson("{\"value\": 174, \"unit\": \"mV/g\"}", "mV/g",
                                      ", \"bogus.tau\": {\"value\": 2, \"unit\": \"ms\"}"));
  const CliResult r = Run(Apply(c, Path("w.csv")));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("triadcal: error: " + c +
                            ": parameters.bogus.tau: unknown effect 'bogus' (this build knows "
                            "angle_latency, ",
                        0),
            0u)
      << r.err;
  EXPECT_NE(r.err.find("); applied without it the correction would be silently wrong: a "
                       "calibration of another build?\n"),
            std::string::npos)
      << r.err;
  WriteText("c.json", CalibrationJson("{\"value\": 174, \"unit\": \"mV/g\"}", "mV/g",
                                      ", \"angle_latency.bogus\": 1"));
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.angle_latency.bogus: unknown parameter of effect angle_latency "
                  "(its parameters: tau)",
              {"w.csv"});
  // "Kx" twice: the last one won.
  WriteText("c.json", CalibrationJson("{\"value\": 174, \"unit\": \"mV/g\"}", "mV/g",
                                      ", \"Kx\": {\"value\": 17.4, \"unit\": \"mV/g\"}"));
  ExpectError(Apply(c, Path("w.csv")),
              c + ": parameters.Kx: given twice (each key once per object; a reader would keep "
                  "only one of them)",
              {"w.csv"});
  ExpectError("export " + c + " --format c -o " + Path("cal.c"),
              c + ": parameters.Kx: given twice (each key once per object; a reader would keep "
                  "only one of them)",
              {"cal.c", "cal.h"});
}

// Only a calibration is applied or exported: the OUT of observability holds
// "parameters" too (nominal values), and was applied and exported with exit 0.
TEST_F(CliReliability, OutputsOfOtherCommandsAreNoCalibration) {
  const std::string obs = Path("obs.json");
  const CliResult o = Run("observability " + Path("run.yaml") + " -o " + obs);
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string expected =
      ": not a calibration (expected an OUT of fit, static, diagnose, filter (\"rts\"), "
      "compare (\"batch\") or a truth.json)";
  ExpectError(Apply(obs, Path("w.csv")), obs + ": command 'observability'" + expected, {"w.csv"});
  ExpectError("export " + obs + " --format json-matrix -o " + Path("m.json"),
              obs + ": command 'observability'" + expected, {"m.json"});
  ExpectError("export " + obs + " --format c -o " + Path("cal.c"),
              obs + ": command 'observability'" + expected, {"cal.c", "cal.h"});
  // Any other command, whatever its parameters hold.
  const std::string c = Path("c.json");
  for (const std::string command : {"montecarlo", "design", "batch", "mounting"}) {
    std::string text = CalibrationJson();
    text.replace(text.find("\"fit\""), 5, "\"" + command + "\"");
    WriteText("c.json", text);
    ExpectError(Apply(c, Path("w.csv")), c + ": command '" + command + "'" + expected, {"w.csv"});
  }
  // The calibrations: fit, static, diagnose (top-level "parameters") are applied.
  for (const std::string command : {"fit", "static", "diagnose"}) {
    std::string text = CalibrationJson();
    text.replace(text.find("\"fit\""), 5, "\"" + command + "\"");
    WriteText("c.json", text);
    const CliResult r = Run(Apply(c, Path("w.csv")));
    EXPECT_EQ(r.exit_code, 0) << command << ": " << r.err;
    fs::remove(Path("w.csv"));
  }
}

// observability with noise_mV: auto takes the readings' own noise as fit does
// (it took the default 2 mV: a CRB 36 times below the fit's sigma on a real run).
TEST_F(CliReliability, ObservabilityWithAutoNoiseUsesTheReadingsNoise) {
  WriteRunCsv(Simulate(testing_fixtures::PaperScenario(50.0, 20.0, 10.0, 15.0, 11)),
              Path("noisy.csv"), "");
  auto kx_crb = [&](const std::string& noise) {
    WriteText("noisy.yaml", "data: noisy.csv\ntriad: {noise_mV: " + noise + "}\n");
    const CliResult r = Run("observability " + Path("noisy.yaml") + " -o " + Path("obs.json") +
                            " --force");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("obs.json")));
    EXPECT_EQ(j["settings"]["noise_auto"].get<bool>(), noise == "auto");
    return j["crb"]["Kx"].get<double>();
  };
  const double declared = kx_crb("10"), auto_noise = kx_crb("auto"), two = kx_crb("2");
  EXPECT_NEAR(auto_noise / declared, 1.0, 0.1) << auto_noise << " vs " << declared;
  EXPECT_GT(auto_noise / two, 3.0) << auto_noise << " vs " << two;
}

// Units follow the run's readings: observability printed and wrote mV/g for a
// run read in counts (its layout was made before the run was read).
TEST_F(CliReliability, ObservabilityUnitsFollowTheReadings) {
  WriteText("counts.yaml",
            "data: run.csv\ncolumns:\n  wx: {source: wx, unit: counts, counts_per_g: 174}\n"
            "  wy: {source: wy, unit: counts, counts_per_g: 174}\n"
            "  wz: {source: wz, unit: counts, counts_per_g: 174}\n");
  ASSERT_EQ(std::system((std::string(TRIADCAL_BIN) + " observability " + Path("counts.yaml") +
                         " -o " + Path("obs.json") + " > " + Path("stdout.txt") + " 2> " +
                         Path("stderr.txt"))
                            .c_str()),
            0)
      << ReadFile(Path("stderr.txt"));
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("obs.json")));
  EXPECT_EQ(j["units"]["Kx"], "counts/g");
  EXPECT_EQ(j["units"]["W0z"], "counts");
  EXPECT_EQ(j["parameters"]["Kx"]["unit"], "counts/g");
  const std::string out = ReadFile(Path("stdout.txt"));
  EXPECT_EQ(out.find("mV"), std::string::npos) << out;
  EXPECT_NE(out.find("counts/g"), std::string::npos) << out;
}

// A run far from its nominal model (offsets of 1500 counts declared 0): the
// filter's covariance loses its positive definiteness. The filter says it
// diverged and where (exit 4, no file); it crashed in the naming of the weak
// directions (an empty matrix to Eigen's eigensolver), and once the
// smoother's backward recursion was gone it wrote the diverged estimates.
// A run.yaml reading `data`'s readings as counts at 174 counts/g with the
// offsets left at 0 (the readings hold 1500).
std::string CountsYaml(const std::string& data) {
  return "data: " + data +
         "\ncolumns:\n  wx: {source: wx, unit: counts, counts_per_g: 174}\n"
         "  wy: {source: wy, unit: counts, counts_per_g: 174}\n"
         "  wz: {source: wz, unit: counts, counts_per_g: 174}\n";
}

TEST_F(CliReliability, DivergedFilterSaysSoAndWritesNothing) {
  WriteText("counts.yaml", CountsYaml("run.csv"));
  const CliResult r = Run("filter " + Path("counts.yaml") + " -o " + Path("out.json"));
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("triadcal: error: " + Path("counts.yaml") +
                       ": the filter diverged (its covariance lost its positive definiteness "
                       "at t = "),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(Path("out.json")));
}

// A run read as counts with offsets of 1500 declared 0, through `fit`: the
// RTS start's filter diverges, so the fit starts from the nominal values with
// the zero offsets fitted, says so, and converges at the truth (it took
// the diverged estimate as its start and stopped there, not converged).
TEST_F(CliReliability, FitStartsFromNominalWhenItsFilterDiverges) {
  const std::string sc = WriteText("sc.yaml", "profile: {duration_s: 20, rate_hz: 100}\n");
  ASSERT_EQ(Run("simulate " + sc + " -o " + Path("sim") + " --seed 11 -q").exit_code, 0);
  WriteText("counts.yaml", CountsYaml("sim/run.csv"));
  const CliResult r = Run("fit " + Path("counts.yaml") + " -o " + Path("out.json"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("triadcal: warning: " + Path("counts.yaml") +
                       ": the RTS smoother diverged (its covariance lost its positive "
                       "definiteness at t = "),
            std::string::npos)
      << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("out.json")));
  EXPECT_TRUE(j["converged"].get<bool>());
  EXPECT_NE(j["initial"]["note"].get<std::string>().find("started from the nominal values"),
            std::string::npos);
  // At the simulated truth: scale factors and offsets within 4 sigma.
  const nlohmann::json truth = nlohmann::json::parse(ReadFile(Path("sim/truth.json")));
  for (const char* name : {"Kx", "Ky", "Kz", "W0x", "W0y", "W0z"}) {
    const nlohmann::json& p = j["parameters"][name];
    EXPECT_LT(std::abs(p["value"].get<double>() - truth["parameters"][name].get<double>()),
              4.0 * p["sigma"].get<double>())
        << name << " " << p.dump();
  }
}

// The point the decision linearises at (and `--init nominal` starts from)
// fits the zero offsets only: the scale factors stay at their nominal
// values, the prior's mean. On this vertical shaft, which determines none of
// them, the misfit of an undeclared 8.6-ms angle latency had moved them
// there to Kx 1006, Ky 1861, Kz 760 mV/g (truth 1004, 996, 1010; on the real
// pitch run Ky went to 22 500 mg/g), and the decision's information is
// formed at that point.
TEST_F(CliReliability, TheDecisionsPointKeepsTheScaleFactorsAtNominal) {
  const std::string sc = WriteText(
      "shaft.yaml",
      "seed: 3\n"
      "profile: {amplitude_deg: [0, 90], period_s: [30, 7.2], duration_s: 120, rate_hz: 100}\n"
      "truth: {Kx: 1004, Ky: 996, Kz: 1010, W0x: 25, W0y: -40, W0z: 60, dtheta_c: 20}\n"
      "noise: {accel_mV: [3, 12, 12], angle_arcsec: 91}\n"
      "effects: {angle_latency: {tau_ms: 8.6}}\n"
      "run:\n"
      "  triad: {scale_mV_per_g: [1000, 1000, 1000], bias_mV: [0, 0, 0], noise_mV: 12}\n"
      "  constraints: []\n");
  ASSERT_EQ(Run("simulate " + sc + " -o " + Path("sim") + " -q").exit_code, 0);
  std::string yaml = ReadFile(Path("sim/run.yaml"));
  WriteText("sim/run.yaml", yaml + "columns:\n  lambda1: {value: 0}\n");
  const CliResult r =
      Run("fit " + Path("sim/run.yaml") + " --init nominal -o " + Path("out.json") + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("out.json")));
  for (const char* k : {"Kx", "Ky", "Kz"}) {
    EXPECT_EQ(j["initial"]["parameters"][k]["value"].get<double>(), 1000.0) << k;
  }
  // The offsets are fitted there (W0x, along the shaft, to its reading's level).
  EXPECT_NEAR(j["initial"]["parameters"]["W0x"]["value"].get<double>(),
              j["parameters"]["W0x"]["value"].get<double>(), 1.0);
}

// The same run through diagnose and batch: each says where its fit started
// (diagnose and batch said nothing; the OUT of fit alone carried the note).
TEST_F(CliReliability, DiagnoseAndBatchSayWhereTheFitStarted) {
  const std::string sc = WriteText("sc.yaml", "profile: {duration_s: 20, rate_hz: 100}\n");
  ASSERT_EQ(Run("simulate " + sc + " -o " + Path("sim") + " --seed 11 -q").exit_code, 0);
  const std::string yaml = WriteText("counts.yaml", CountsYaml("sim/run.csv"));
  const std::string note =
      ": the RTS smoother diverged (its covariance lost its positive definiteness at t = ";
  const CliResult d = Run("diagnose " + yaml + " -o " + Path("d.json"));
  EXPECT_EQ(d.exit_code, 0) << d.err;
  EXPECT_NE(d.err.find("triadcal: warning: " + yaml + note), std::string::npos) << d.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("d.json")));
  EXPECT_NE(j["before"]["initial"]["note"].get<std::string>().find("started from the nominal"),
            std::string::npos);
  WriteText("manifest.csv", "serial,run\nC1,counts.yaml\n");
  const CliResult b =
      Run("batch " + Path("manifest.csv") + " -o " + Path("b") + " --date 2024-01-02");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  std::string summary;
  for (const auto& e : fs::directory_iterator(Path("b"))) {
    if (e.path().extension() == ".json") summary = ReadFile(e.path().string());
  }
  const nlohmann::json s = nlohmann::json::parse(summary);
  ASSERT_EQ(s["results"].size(), 1u);
  bool said = false;
  for (const auto& w : s["results"][0]["warnings"]) {
    said = said || w.get<std::string>().find(note) != std::string::npos;
  }
  EXPECT_TRUE(said) << s["results"][0]["warnings"].dump();
}

// The same misdeclared counts run, shorter (the paper's experiment, 20 s at
// 50 Hz, seed 3): the smoother, its offsets of 0 far from the readings'
// 1500 counts, estimates nonlinearities under which the readings model no
// longer inverts. That is its divergence (the inverse is not a number there:
// SpecificForceFromReadings_g); the fit starts from the nominal values with
// the zero offsets fitted, converges, finds the simulated sensor and says the
// declared offsets are wrong. Before, the inverse's last iterate was taken:
// the smoother lost the track without diverging, and the fit from its
// estimates headed for a degenerate optimum (Kz towards 0) and did not
// converge in 40 steps.
TEST_F(CliReliability, FitFromALostStartRecovers) {
  std::string sc = ReadFile(std::string(TRIADCAL_SOURCE_DIR) +
                            "/examples/paper-experiment3/scenario.yaml");
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"duration_s: 90 ",
                                                                     "duration_s: 20 "},
                                 {"rate_hz: 1000 ", "rate_hz: 50 "}}) {
    ASSERT_NE(sc.find(from), std::string::npos) << from;
    sc.replace(sc.find(from), from.size(), to);
  }
  WriteText("sc.yaml", sc);
  ASSERT_EQ(Run("simulate " + Path("sc.yaml") + " -o " + Path("sim") + " --seed 3 -q").exit_code,
            0);
  WriteText("counts.yaml", CountsYaml("sim/run.csv"));
  const CliResult r = Run("fit " + Path("counts.yaml") + " -o " + Path("out.json"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("the RTS smoother diverged"), std::string::npos) << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("out.json")));
  EXPECT_TRUE(j["converged"].get<bool>()) << j["verdict"]["termination"];
  const nlohmann::json truth = nlohmann::json::parse(ReadFile(Path("sim/truth.json")));
  for (const std::string k : {"Kx", "Ky", "Kz", "W0x", "W0y", "W0z"}) {
    const double value = j["parameters"][k]["value"].get<double>();
    const double sigma = j["parameters"][k]["sigma"].get<double>();
    EXPECT_LT(std::abs(value - truth["parameters"][k].get<double>()), 4.0 * sigma) << k;
  }
  EXPECT_NE(j["verdict"]["beyond_prior"].dump().find("\"W0x\""), std::string::npos)
      << j["verdict"].dump();
}

// batch names its units for each run's readings: Kx was "mV/g" for counts.
TEST_F(CliReliability, BatchUnitsFollowEachRunsReadings) {
  CliResult r_failed;
  WriteText("counts.yaml",
            "data: run.csv\ncolumns:\n  wx: {source: wx, unit: counts, counts_per_g: 174}\n"
            "  wy: {source: wy, unit: counts, counts_per_g: 174}\n"
            "  wz: {source: wz, unit: counts, counts_per_g: 174}\n");
  WriteText("counts.csv", "serial,run\nC1,counts.yaml\n");
  // Not converged (the nominal offsets of counts are 0, these are 1500): an
  // error naming the verdict, not an internal error (exit 3).
  r_failed = Run("batch " + Path("counts.csv") + " -o " + Path("bad") + " --date 2024-01-02");
  EXPECT_EQ(r_failed.exit_code, 0) << r_failed.err;
  EXPECT_EQ(r_failed.err, "");
  WriteText("counts.yaml",
            "data: run.csv\ntriad: {bias_mV: [1500, 1500, 1500]}\ncolumns:\n"
            "  wx: {source: wx, unit: counts, counts_per_g: 174}\n"
            "  wy: {source: wy, unit: counts, counts_per_g: 174}\n"
            "  wz: {source: wz, unit: counts, counts_per_g: 174}\n");
  WriteText("mixed.csv", "serial,run\nC1,counts.yaml\nM1,run.yaml\n");
  auto kx_unit = [&](const std::string& dir, const std::string& serial) {
    for (const auto& d : fs::recursive_directory_iterator(Path(dir))) {
      if (d.path().filename() == "calibration.json" &&
          d.path().parent_path().parent_path().filename() == serial) {
        return nlohmann::json::parse(ReadFile(d.path().string()))["parameters"]["Kx"]["unit"]
            .get<std::string>();
      }
    }
    return std::string("none");
  };
  CliResult r = Run("batch " + Path("counts.csv") + " -o " + Path("one") + " --date 2024-01-02");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(kx_unit("one", "C1"), "counts/g");
  r = Run("batch " + Path("mixed.csv") + " -o " + Path("two") + " --date 2024-01-02");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(kx_unit("two", "C1"), "counts/g");
  EXPECT_EQ(kx_unit("two", "M1"), "mV/g");
}

TEST_F(CliReliability, CorrectedForceFarFromOneGIsAWarning) {
  // Scale factors 1.5 times the sensor's: within the bound, but |W| ~ 0.67 g.
  const std::string c =
      WriteText("c.json", CalibrationJson("{\"value\": 261, \"unit\": \"mV/g\"}", "mV/g", "", 261));
  const CliResult r = Run(Apply(c, Path("w.csv")));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.rfind("triadcal: warning: " + Path("run.yaml") + ": corrected with " + c +
                            ", |W| has the median 0.6",
                        0),
            0u)
      << r.err;
  EXPECT_NE(r.err.find(" g, where a bench at rest gives 1 g (bound +-0.1 g): a calibration of "
                       "another sensor, in other units or for another mounting?\n"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // The matching calibration: no word.
  const CliResult ok = Run(Apply(Path("cal.json"), Path("w2.csv")));
  EXPECT_EQ(ok.exit_code, 0);
  EXPECT_EQ(ok.err, "");
}

TEST_F(CliReliability, ExportedCCompilesUnderAnotherName) {
  if (std::system("cc --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "no C compiler";
  const CliResult r =
      Run("export " + Path("cal.json") + " --format c --name mycal -o " + Path("other.c"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(Path("other.h")));
  EXPECT_NE(ReadFile(Path("other.c")).find("#include \"other.h\""), std::string::npos);
  EXPECT_EQ(std::system(("cc -std=c99 -c " + Path("other.c") + " -o " + Path("other.o") + " 2> " +
                         Path("cc.txt"))
                            .c_str()),
            0)
      << ReadFile(Path("cc.txt"));
}

// ---- static: positions distinct and as the data say

class StaticPositions : public CliReliability {
 protected:
  // Six positions of 3 s at 50 Hz on a triad of 174 mV/g, 1500 mV, 1 mV
  // noise, with moving samples between them; `labels` in the order x_p, x_a,
  // y_p, y_a, z_p, z_a (the up directions +x, -x, +y, -y, +z, -z).
  std::string LabelledRun(const std::vector<std::string>& labels) {
    const Eigen::Vector3d ups[6] = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                    Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                    Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()};
    std::mt19937_64 rng(5);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::ostringstream csv;
    csv << "t,part,wx,wy,wz\n";
    int k = 0;
    for (int p = 0; p < 6; ++p) {
      for (int j = 0; j < 150; ++j, ++k) {
        csv << 0.02 * k << "," << labels[p];
        for (int i = 0; i < 3; ++i) csv << "," << 1500.0 + 174.0 * ups[p][i] + noise(rng);
        csv << "\n";
      }
      for (int j = 0; j < 50; ++j, ++k) {  // turning to the next face
        csv << 0.02 * k << ",moving";
        for (int i = 0; i < 3; ++i) csv << "," << 1500.0 + 174.0 * std::sin(0.3 * k + i);
        csv << "\n";
      }
    }
    WriteText("static.csv", csv.str());
    return "data: static.csv\ncolumns: {lambda1: {value: 0}, lambda2: {value: 0}, label: part}\n"
           "triad: {noise_mV: 1}\nconstraints: []\n";
  }
  std::string Static(const std::string& yaml) {
    return "static " + WriteText("s.yaml", yaml) + " -o " + Path("out.json");
  }
};

TEST_F(StaticPositions, TheSixLabelledPositionsFit) {
  const CliResult r = Run(Static(LabelledRun({"x_p", "x_a", "y_p", "y_a", "z_p", "z_a"})));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

TEST_F(StaticPositions, TwoPositionsDeclaredTheSameWay) {
  ExpectError(Static(LabelledRun({"x_p", "x_a", "y_p", "y_a", "z_p", "z_a"}) +
                     "positions: {x_p: \"+x\", x_a: \"+x\", y_p: \"+y\", y_a: \"-y\", z_p: "
                     "\"+z\", z_a: \"-z\"}\n"),
              Path("s.yaml") +
                  ": positions.x_a: points the same way as positions.x_p (two "
                  "positions need two directions; one label written twice, or a "
                  "sign lost?)");
}

TEST_F(StaticPositions, SwappedLabelsAreRefused) {
  // x_p and x_a swapped in the data: Kx = -171.5 mV/g "with a perfect fit".
  ExpectError(Static(LabelledRun({"x_a", "x_p", "y_p", "y_a", "z_p", "z_a"})),
              Path("s.yaml") +
                  ": positions.x_a: declared -x up, but its still readings have "
                  "gravity along +x (platform axes, 180 deg away; bound 45 deg): are "
                  "the labels x_a and x_p swapped?");
}

TEST_F(StaticPositions, UnknownPositionLabelIsNotDropped) {
  const std::string run = LabelledRun({"x_p", "x_n", "y_p", "y_a", "z_p", "z_a"});
  const CliResult r = Run(Static(run));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("triadcal: error: " + Path("s.yaml") +
                            ": positions: label 'x_n' of column 'part' holds ",
                        0),
            0u)
      << r.err;
  EXPECT_NE(r.err.find(" s of still data but is no declared position (positions: x_a, x_p, y_a, "
                       "y_p, z_a, z_p): give the direction that points up in it, or `x_n: none` "
                       "if it is no position\n"),
            std::string::npos)
      << r.err;
  // Declared, it is a position; `none` would say it is not one.
  const CliResult ok = Run(Static(run + "positions: {x_p: \"+x\", x_n: \"-x\", y_p: \"+y\", y_a: "
                                        "\"-y\", z_p: \"+z\", z_a: \"-z\"}\n"));
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

// ---- plausibility

TEST_F(CliReliability, SimulatedReadingsMustBeFinite) {
  const std::string sc =
      WriteText("sc.yaml", "profile: {amplitude_deg: [1e300, 90], duration_s: 2, rate_hz: 20}\n");
  char peak[64];
  std::snprintf(peak, sizeof(peak), "%g", 1e300 * 2.0 * kPi / 30.0);
  ExpectError("simulate " + sc + " -o " + Path("sim"),
              sc + ": profile.amplitude_deg[0]: 1e+300 deg over a period of 30 s swings at up to " +
                  peak + " deg/s, beyond the bound 3600 deg/s of run data",
              {"sim"});
  // A truth value that overflows the readings.
  const std::string huge =
      WriteText("huge.yaml", "profile: {duration_s: 2, rate_hz: 20}\ntruth: {Kxx: 1e308}\n");
  ExpectError("simulate " + huge + " -o " + Path("sim"),
              huge +
                  ": the simulated readings at t = 0 s are not finite numbers: check the "
                  "profile and truth values (a number beyond what the model can evaluate)",
              {"sim"});
}

TEST_F(CliReliability, ImplausibleFitResultIsAWarningNamingTheCause) {
  // The inner angle-sensor zero 5 deg off while the constraint dpsi - dlambda2
  // = 0 levels the bench: the fit puts it into gamma_y (442' in the corpus).
  Scenario s = testing_fixtures::PaperScenario(50.0, 30.0, 2.0, 15.0, 11);
  SetFromFileUnits(s.truth_layout, {{"dlambda2", -300.0}, {"dpsi", 0.0}}, &s.truth);
  WriteRunCsv(Simulate(s), Path("zero.csv"), "");
  WriteText("zero.yaml",
            "data: zero.csv\ntriad: {scale_mV_per_g: [174, 174, 174], bias_mV: [1500, 1500, "
            "1500], noise_mV: 2}\nbench: {angle_noise_arcsec: 15}\n");
  const CliResult r =
      Run("fit " + Path("zero.yaml") + " -o " + Path("out.json") + " -q --no-auto-hold");
  EXPECT_NE(r.err.find("triadcal: warning: " + Path("out.json") + ": parameters.gamma_"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("is beyond what a triad's axes can be off (3 deg): likely an inner "
                       "angle-sensor zero (columns.lambda2.offset) held by a levelling "
                       "constraint (dpsi - dlambda2) that does not hold for this bench, or a "
                       "wrong mounting; a result this far outside the plausible is no "
                       "calibration\n"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace triadcal

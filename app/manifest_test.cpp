#include "app/manifest.h"

#include <gtest/gtest.h>

#include "core/model/errors.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

class ManifestTest : public testing_fixtures::TempDirTest {
 protected:
  // The one-line error LoadManifest gives for `text` written to `name`.
  std::string ErrorOf(const std::string& name, const std::string& text) {
    const std::string path = WriteText(name, text);
    try {
      LoadManifest(path);
    } catch (const InputError& e) {
      const std::string what = e.what();
      return what.rfind(path, 0) == 0 ? "FILE" + what.substr(path.size()) : what;
    }
    return "no error";
  }
};

TEST_F(ManifestTest, CsvWithLimitsAndComments) {
  const std::string path = WriteText("m.csv",
                                     "# line A\n"
                                     "serial, run, diagnose, Kx_min, Kx_max, W0x_sigma_max\n"
                                     "A001,a/run.yaml,false,165,185,\n"
                                     "\n"
                                     "A-2.b,b/run.yaml,true,,,0.5\n");
  const std::vector<ManifestEntry> m = LoadManifest(path);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].serial, "A001");
  EXPECT_EQ(m[0].run, "a/run.yaml");
  EXPECT_EQ(m[0].run_path, Path("a/run.yaml"));
  EXPECT_FALSE(m[0].diagnose);
  ASSERT_EQ(m[0].limits.size(), 1u);
  EXPECT_EQ(m[0].limits[0].parameter, "Kx");
  EXPECT_EQ(*m[0].limits[0].min, 165);
  EXPECT_EQ(*m[0].limits[0].max, 185);
  EXPECT_FALSE(m[0].limits[0].sigma_max);
  EXPECT_TRUE(m[1].diagnose);
  ASSERT_EQ(m[1].limits.size(), 1u);
  EXPECT_EQ(m[1].limits[0].parameter, "W0x");
  EXPECT_EQ(*m[1].limits[0].sigma_max, 0.5);
}

TEST_F(ManifestTest, YamlDefaultsAndPerRunLimits) {
  const std::string path =
      WriteText("m.yaml",
                "limits: {Kx: {min: 165, max: 185}, angle_latency.tau: {max: 3}}\n"
                "diagnose: true\n"
                "runs:\n"
                "  - {serial: A1, run: a/run.yaml}\n"
                "  - {serial: A2, run: b/run.yaml, diagnose: false, limits: {Kx: {max: 180}}}\n");
  const std::vector<ManifestEntry> m = LoadManifest(path);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_TRUE(m[0].diagnose);
  EXPECT_FALSE(m[1].diagnose);
  ASSERT_EQ(m[1].limits.size(), 2u);
  EXPECT_EQ(m[1].limits[0].parameter, "Kx");
  EXPECT_FALSE(m[1].limits[0].min);  // the run's own limit replaces the default
  EXPECT_EQ(*m[1].limits[0].max, 180);
  EXPECT_EQ(*m[1].limits[1].max, 3);
}

TEST_F(ManifestTest, BadManifestsSayWhereAndWhat) {
  EXPECT_EQ(ErrorOf("a.csv", "serial,run,Kq_max\n"),
            "FILE:1: Kq_max: unknown column (serial, run, diagnose, or PARAM_min, PARAM_max, "
            "PARAM_sigma_max with PARAM a parameter name of SPEC section 3)");
  EXPECT_EQ(ErrorOf("b.csv", "run,Kx_max\n"), "FILE:1: serial: missing column");
  EXPECT_EQ(ErrorOf("c.csv", "serial,run,Kx_max\nA1,r.yaml,abc\n"),
            "FILE:2: Kx_max: expected a number, got 'abc'");
  EXPECT_EQ(ErrorOf("d.csv", "serial,run\n# c\nA1,r.yaml,3\n"),
            "FILE:3: expected 2 cells as the header on line 1, got 3");
  EXPECT_EQ(ErrorOf("e.csv", "serial,run\n../x,r.yaml\n"),
            "FILE:2: serial: '../x' cannot name a folder (letters, digits, '.', '_', '-'; not "
            "starting with '.')");
  EXPECT_EQ(ErrorOf("f.csv", "serial,run,Kx_min,Kx_max\nA,r.yaml,5,4\n"),
            "FILE:2: Kx: min 5 is above max 4");
  EXPECT_EQ(ErrorOf("g.csv", "serial,run,diagnose\nA,r.yaml,maybe\n"),
            "FILE:2: diagnose: expected true or false, got 'maybe'");
  EXPECT_EQ(ErrorOf("h.csv", "# nothing\n"), "FILE: empty manifest (expected a header line)");
  EXPECT_EQ(ErrorOf("a.yaml", "runs:\n  - {serial: A, run: r.yaml, limits: {Kq: {max: 1}}}\n"),
            "FILE: runs[0].limits.Kq: unknown parameter (names of SPEC section 3)");
  EXPECT_EQ(ErrorOf("b.yaml", "runs:\n  - {run: r.yaml}\n"), "FILE: runs[0].serial: missing");
  EXPECT_EQ(ErrorOf("c.yaml", "runs:\n  - {serial: 'a b', run: r.yaml}\n"),
            "FILE: runs[0].serial: 'a b' cannot name a folder (letters, digits, '.', '_', '-'; "
            "not starting with '.')");
  EXPECT_EQ(ErrorOf("d.yaml", "limits: {Kx: {min: 3, max: 2}}\nruns: []\n"),
            "FILE: limits.Kx: min 3 is above max 2");
  EXPECT_EQ(ErrorOf("m.txt", "serial,run\n"), "FILE: manifest: expected a .csv or .yaml file");
}

}  // namespace
}  // namespace triadcal

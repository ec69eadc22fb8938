// The export job (app/export_job.h): the format both ways, the C names
// refused with the option that gave them, and the same files as `triadcal
// export` (their provenance aside).
#include "app/export_job.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tests/cli_test.h"
#include "tests/error_of.h"

namespace triadcal {
namespace {

using testing_fixtures::Comparable;

using testing_fixtures::ErrorOf;

// The text without its provenance lines (the command line, date, inputs).
std::string WithoutProvenance(const std::string& text) {
  std::istringstream in(text);
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.find("provenance") == std::string::npos) out += line + "\n";
  }
  return out;
}

TEST(ExportSettings, FormatBothWaysAndNames) {
  for (ExportFormat f : {ExportFormat::kC, ExportFormat::kYaml, ExportFormat::kJsonMatrix}) {
    EXPECT_EQ(ParseExportFormat(ExportFormatName(f)), f);
  }
  EXPECT_EQ(ErrorOf([] { ParseExportFormat("xml"); }),
            "--format: expected c, yaml or json-matrix, got 'xml'");
  ExportSettings s;
  s.name = "1x";
  EXPECT_EQ(ErrorOf([&] { s.Validate(); }),
            "--name: '1x' is not a C identifier (the function is NAME_apply); use --name");
  s.name = "imu_7";
  EXPECT_EQ(ErrorOf([&] { s.Validate(); }), "");
}

class ExportJob : public testing_fixtures::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    // The 21 sensor parameters a calibration needs.
    cal_ = WriteText("truth.json",
                     "{\"parameters\": {\"Kx\": 171.5, \"Ky\": 175.8, \"Kz\": 174.8, "
                     "\"W0x\": 1504.2, \"W0y\": 1498.0, \"W0z\": 1502.5, \"alpha_x\": 16, "
                     "\"alpha_y\": -32, \"beta_x\": 11, \"beta_z\": 26, \"gamma_y\": 140, "
                     "\"gamma_z\": 64, \"Kxx\": 0.002, \"Kxy\": 0, \"Kxz\": 0, \"Kyx\": 0, "
                     "\"Kyy\": 0, \"Kyz\": -0.001, \"Kzx\": 0, \"Kzy\": 0.0015, \"Kzz\": 0}}");
  }
  ExportOutcome Job(ExportFormat format, const std::string& file_base = "cal") {
    ExportSettings s;
    s.format = format;
    Session session;
    return ExportRun(s, cal_, file_base, &session);
  }
  std::string cal_;
};

TEST_F(ExportJob, SameFilesAsTheCommandLine) {
  testing_fixtures::CliResult cli =
      Run("export " + cal_ + " --format json-matrix -o " + Path("m.json"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_EQ(Comparable(Job(ExportFormat::kJsonMatrix).json), Out("m.json"));

  cli = Run("export " + cal_ + " --format yaml -o " + Path("m.yaml"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_EQ(WithoutProvenance(Job(ExportFormat::kYaml).yaml),
            WithoutProvenance(ReadFile(Path("m.yaml"))));

  cli = Run("export " + cal_ + " --format c -o " + Path("cal.c"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  const ExportOutcome c = Job(ExportFormat::kC);
  EXPECT_EQ(c.name, "cal");
  EXPECT_EQ(WithoutProvenance(c.c.header), WithoutProvenance(ReadFile(Path("cal.h"))));
  EXPECT_EQ(WithoutProvenance(c.c.source), WithoutProvenance(ReadFile(Path("cal.c"))));
}

TEST_F(ExportJob, AFileNameThatIsNoIdentifierNamesTheOutput) {
  EXPECT_EQ(ErrorOf([&] { Job(ExportFormat::kC, "1cal"); }),
            "-o: file name '1cal' is not a C identifier (the function is NAME_apply); use --name");
  EXPECT_EQ(ErrorOf([&] { Job(ExportFormat::kYaml, "1cal"); }), "");  // no function there
}

}  // namespace
}  // namespace triadcal

// The apply job (app/apply_job.h): the CSV of `triadcal apply`, the
// warnings it gives, and a file that is not a calibration refused by name.
#include "app/apply_job.h"

#include <gtest/gtest.h>

#include <string>

#include "app/fit_job.h"
#include "app/output_guard.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tests/cli_test.h"

namespace triadcal {
namespace {

// The CSV without its provenance line (the version and time of the writer).
std::string WithoutProvenance(const std::string& csv) {
  const std::size_t at = csv.find("# provenance: ");
  return at == std::string::npos ? csv : csv.substr(0, at) + csv.substr(csv.find('\n', at) + 1);
}

class ApplyJob : public testing_fixtures::CliTest {
 protected:
  // cal.json: the fit job's OUT of run.yaml.
  std::string Calibrate() const {
    Session session;
    const std::string run_yaml = Path("run.yaml");
    const FitOutcome f = FitRun(FitSettings(), run_yaml, LoadRun(run_yaml, &session), session);
    WriteJsonFile(f.json, Path("cal.json"), session);
    return Path("cal.json");
  }
};

TEST_F(ApplyJob, SameCsvAsTheCommandLine) {
  const std::string cal = Calibrate();
  const testing_fixtures::CliResult cli =
      Run("apply " + cal + " " + Path("run.yaml") + " -o " + Path("w.csv"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  Session session;
  const ApplyOutcome o = ApplyRun(cal, Path("run.yaml"), &session);
  EXPECT_TRUE(o.warnings.empty());
  EXPECT_FALSE(o.gyro);
  EXPECT_EQ(o.W_g.size(), o.samples);
  EXPECT_NEAR(o.W_g[0].norm(), 1.0, 0.05);
  EXPECT_EQ(WithoutProvenance(o.csv), WithoutProvenance(ReadFile(Path("w.csv"))));
}

TEST_F(ApplyJob, ScalesOfAnotherSensorAreAWarning) {
  nlohmann::json j = nlohmann::json::parse(ReadFile(Calibrate()));
  for (const char* k : {"Kx", "Ky", "Kz"}) {
    j["parameters"][k]["value"] = 1.5 * j["parameters"][k]["value"].get<double>();
  }
  const std::string cal = WriteText("big.json", j.dump());
  Session session;
  const ApplyOutcome o = ApplyRun(cal, Path("run.yaml"), &session);
  ASSERT_EQ(o.warnings.size(), 1u);
  EXPECT_EQ(o.warnings[0].rfind(Path("run.yaml") + ": corrected with " + cal +
                                    ", |W| has the median 0.6",
                                0),
            0u)
      << o.warnings[0];
}

TEST_F(ApplyJob, NotACalibrationIsRefusedByName) {
  const std::string not_cal = WriteText("unit.json", "{\"serial\": \"A1\"}");
  Session session;
  try {
    ApplyRun(not_cal, Path("run.yaml"), &session);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              not_cal + ": parameters: missing (expected an OUT of fit, static, diagnose, "
                        "filter (\"rts\"), compare (\"batch\") or a truth.json)");
  }
}

}  // namespace
}  // namespace triadcal

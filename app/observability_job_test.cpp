// The observability job (app/observability_job.h): one Validate naming the
// option, and the same OUT as `triadcal observability` on a run, on a
// scenario and on two runs together.
#include "app/observability_job.h"

#include <gtest/gtest.h>

#include <string>

#include "core/model/errors.h"
#include "tests/cli_test.h"
#include "tests/error_of.h"

namespace triadcal {
namespace {

using testing_fixtures::Comparable;
using testing_fixtures::ValidateError;

TEST(ObservabilitySettings, ValidateNamesTheOption) {
  EXPECT_EQ(ValidateError(ObservabilitySettings()), "");
  ObservabilitySettings s;
  s.unobservable_below = 2.0;
  s.weak_below = 1.0;
  EXPECT_EQ(ValidateError(s),
            "--unobservable-below, --weak-below: expected 0 < unobservable <= weak");
  s = ObservabilitySettings();
  s.alpha = 1.0;
  EXPECT_EQ(ValidateError(s), "--alpha: must be in (0, 1)");
  s = ObservabilitySettings();
  s.threads = -1;
  EXPECT_EQ(ValidateError(s), "--threads: Value -1 not in range 0 to 1024");
  s = ObservabilitySettings();
  s.effects = "nonsense";
  EXPECT_EQ(ValidateError(s).rfind("--effects: unknown effect 'nonsense' (known: ", 0), 0u)
      << ValidateError(s);
}

class ObservabilityJob : public testing_fixtures::CliTest {
 protected:
  nlohmann::json JobOut(const ObservabilitySettings& s, const std::string& input) {
    Session session;
    const ObservabilityInput in = LoadObservabilityInput(input, s.effects, &session);
    return Comparable(ObservabilityRun(s, in, session).json);
  }
};

TEST_F(ObservabilityJob, SameOutAsTheCommandLine) {
  const std::string run_yaml = Path("run.yaml");
  testing_fixtures::CliResult cli = Run("observability " + run_yaml +
                                        " --effects thermal_drift "
                                        "--weak-below 5 -o " +
                                        Path("out.json"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  ObservabilitySettings s;
  s.effects = "thermal_drift";
  s.weak_below = 5.0;
  EXPECT_EQ(JobOut(s, run_yaml), Out("out.json"));

  // A scenario's profile, at its truth.
  const std::string scenario = WriteText(
      "scenario.yaml",
      "profile: {amplitude_deg: [360, 90], period_s: [30, 12], duration_s: 20, rate_hz: 25}\n"
      "truth: {Kx: 171.5, W0x: 1504.2}\n"
      "noise: {accel_mV: 2, angle_arcsec: 15}\n");
  cli = Run("observability " + scenario + " -o " + Path("scenario.json"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  const nlohmann::json job = JobOut(ObservabilitySettings(), scenario);
  EXPECT_EQ(job["evaluated_at"], "truth");
  EXPECT_EQ(job, Out("scenario.json"));
}

TEST_F(ObservabilityJob, RunsTogetherSameOutAsTheCommandLine) {
  // A second run: the same profile, other noise.
  WriteRunCsv(Simulate(testing_fixtures::PaperScenario(50.0, 20.0, 2.0, 15.0, 12)),
              Path("again.csv"), "");
  const std::string run_yaml = Path("run.yaml"),
                    again = WriteText("again.yaml", "data: again.csv\n");
  const testing_fixtures::CliResult cli =
      Run("observability " + run_yaml + " " + again + " -o " + Path("out.json"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  Session session;
  JointInput in = LoadJointInput({run_yaml, again}, "", &session);
  const JointObservabilityOutcome o = JointObservabilityRun(ObservabilitySettings(), &in, session);
  EXPECT_EQ(o.json["kind"], "joint");
  EXPECT_EQ(Comparable(o.json), Out("out.json"));
}

}  // namespace
}  // namespace triadcal

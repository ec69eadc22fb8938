// The filter job (app/filter_job.h): one Validate naming the option, the
// same OUT as `triadcal filter`, and the fit job's hold decision.
#include "app/filter_job.h"

#include <gtest/gtest.h>

#include <string>

#include "app/fit_job.h"
#include "core/model/errors.h"
#include "tests/cli_test.h"
#include "tests/error_of.h"

namespace triadcal {
namespace {

using testing_fixtures::Comparable;
using testing_fixtures::ValidateError;

TEST(FilterSettings, ValidateNamesTheOption) {
  EXPECT_EQ(ValidateError(FilterSettings()), "");
  FilterSettings s;
  s.iterations = 0;
  EXPECT_EQ(ValidateError(s), "--iterations: Value 0 not in range 1 to 20");
  s = FilterSettings();
  s.hold = {"dpsi"};
  s.free = {"dpsi"};
  EXPECT_EQ(ValidateError(s), "--hold/--free: 'dpsi' given to both: hold it or free it");
  s = FilterSettings();
  s.effects = "thermal_drift,nonsense";
  EXPECT_EQ(ValidateError(s).rfind("--effects: unknown effect 'nonsense' (known: ", 0), 0u)
      << ValidateError(s);
  s = FilterSettings();
  s.rate_window_s = 0.0;
  EXPECT_EQ(ValidateError(s).rfind("--rate-window-s: ", 0), 0u) << ValidateError(s);
}

class FilterJob : public testing_fixtures::CliTest {};

TEST_F(FilterJob, SameOutAsTheCommandLine) {
  const std::string run_yaml = Path("run.yaml");
  const testing_fixtures::CliResult cli =
      Run("filter " + run_yaml + " --iterations 1 -o " + Path("out.json"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  Session session;
  const LoadedRun run = LoadRun(run_yaml, &session);
  FilterSettings s;
  s.iterations = 1;
  const FilterOutcome f = FilterRun(s, run_yaml, run, session);
  ASSERT_EQ(f.error, "");
  EXPECT_EQ(Comparable(f.json), Out("out.json"));
}

// The filter holds (at nominal) what the fit job holds or considers: on a
// roll about the outer axis alone, which leaves parameters undetermined.
TEST_F(FilterJob, HoldsWhatTheFitHolds) {
  Scenario roll = testing_fixtures::PaperScenario(50.0, 20.0, 2.0, 15.0, 3);
  roll.profile.amplitude_rad[1] = 0.0;
  WriteRunCsv(Simulate(roll), Path("roll.csv"), "");
  const std::string run_yaml = WriteText("roll.yaml", "data: roll.csv\n");
  Session session;
  const LoadedRun run = LoadRun(run_yaml, &session);
  FilterSettings s;
  s.iterations = 1;
  const FilterOutcome f = FilterRun(s, run_yaml, run, session);
  const FitOutcome fit = FitRun(FitSettings(), run_yaml, run, session);
  EXPECT_FALSE(fit.result.held.empty() && fit.result.consider.empty());
  EXPECT_EQ(f.decision.held, fit.result.held);
  EXPECT_EQ(f.decision.consider, fit.result.consider);
  EXPECT_EQ(f.pinned.size(), fit.result.held.size() + fit.result.consider.size());
}

// noise_mV: auto: the filter runs and decides at the readings' own white
// noise per channel, as fit starts from (before, at the declared start: a run
// with 6 mV of noise was filtered at the default figure, and the filter held
// other parameters than fit); a declared figure is used as it is.
TEST_F(FilterJob, AutoNoiseIsTheReadingsOwn) {
  Scenario roll = testing_fixtures::PaperScenario(50.0, 20.0, 6.0, 15.0, 4);
  roll.profile.amplitude_rad[1] = 0.0;
  WriteRunCsv(Simulate(roll), Path("roll.csv"), "");
  Session session;
  FilterSettings s;
  s.iterations = 1;
  const std::string auto_yaml = WriteText("auto.yaml", "data: roll.csv\ntriad: {noise_mV: auto}\n");
  const LoadedRun run = LoadRun(auto_yaml, &session);
  const FilterOutcome f = FilterRun(s, auto_yaml, run, session);
  ASSERT_EQ(f.error, "");
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(f.noise[i], 6.0, 0.6) << i;
  EXPECT_EQ(f.json["settings"]["noise"]["auto"], true);
  EXPECT_EQ(f.json["settings"]["noise"]["unit"], "mV");
  const FitOutcome fit = FitRun(FitSettings(), auto_yaml, run, session);
  EXPECT_EQ(f.decision.held, fit.result.held);
  EXPECT_EQ(f.decision.consider, fit.result.consider);

  const std::string declared_yaml =
      WriteText("declared.yaml", "data: roll.csv\ntriad: {noise_mV: 1.5}\n");
  const FilterOutcome d = FilterRun(s, declared_yaml, LoadRun(declared_yaml, &session), session);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(d.noise[i], 1.5) << i;
  EXPECT_EQ(d.json["settings"]["noise"]["auto"], false);
}

}  // namespace
}  // namespace triadcal

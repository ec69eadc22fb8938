// The compare job (app/compare_job.h): one Validate naming the option, and
// the same OUT as `triadcal compare`.
#include "app/compare_job.h"

#include <gtest/gtest.h>

#include <string>

#include "core/model/errors.h"
#include "tests/cli_test.h"

namespace triadcal {
namespace {

using testing_fixtures::Comparable;

TEST(CompareSettings, ValidateNamesTheOption) {
  CompareSettings s;
  EXPECT_NO_THROW(s.Validate());
  s.effects = "thermal_drift, nonsense";
  try {
    s.Validate();
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--effects: unknown effect 'nonsense' (known: ", 0), 0u)
        << e.what();
  }
}

class CompareJob : public testing_fixtures::CliTest {};

TEST_F(CompareJob, SameOutAsTheCommandLine) {
  const std::string run_yaml = Path("run.yaml");
  const testing_fixtures::CliResult cli = Run("compare " + run_yaml + " -o " + Path("out.json"));
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  Session session;
  const LoadedRun run = LoadRun(run_yaml, &session);
  const CompareOutcome c = CompareRun(CompareSettings(), run_yaml, run, session);
  ASSERT_EQ(c.error, "");
  EXPECT_EQ(Comparable(c.json), Out("out.json"));
  // The batch left out what the filter held.
  EXPECT_EQ(c.batch.held, c.filter.decision.held);
  EXPECT_EQ(c.batch.consider, c.filter.decision.consider);
}

}  // namespace
}  // namespace triadcal

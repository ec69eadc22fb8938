// `triadcal observability SCENARIO.yaml --could-hide` (issue 12): what the loop
// could miss on a planned profile, before any run -- the same list `diagnose`
// gives after a run of that profile -- and its refusal on a recorded run.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "core/io/file_util.h"
#include "core/model/effects.h"
#include "tests/cli_scenarios.h"
#include "tests/command_runner.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;
using testing_fixtures::RunTriadcal;

class CouldHideCli : public testing_fixtures::TempDirTest {
 protected:
  std::string Scenario() {
    return WriteText("scenario.yaml", testing_fixtures::kPaper60sScenario);
  }
};

// The planned profile's list: every catalogue effect the run could carry
// (no temp_C: not the temperature drift), each with a finite minimal size or
// the note that the profile cannot detect it; the encoder harmonic, nearly a
// reparametrisation of the base model, moves some parameter by more than 1
// sigma. diagnose on a noisy run of the same profile gives the same effects
// with the same minimal sizes to 10 % (the list is the profile's).
TEST_F(CouldHideCli, PlannedProfileGivesDiagnosesList) {
  const std::string sc = Scenario();
  const auto r = RunTriadcal(
      "observability " + sc + " --could-hide -o " + Path("obs.json"), Path("obs.err"));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(Path("obs.json")));
  ASSERT_TRUE(j.contains("could_hide"));
  const nlohmann::json& h = j["could_hide"];
  // The catalogue less thermal_drift_temp and the gyro's effects (no gyro here).
  std::size_t expected = 0;
  for (const EffectSpec& e : EffectCatalogue()) {
    expected += e.id != Effect::kThermalDriftTemp && e.stage != EffectStage::kGyro ? 1 : 0;
  }
  EXPECT_EQ(h.size(), expected);
  std::map<std::string, double> planned;
  double largest_shift = 0.0;
  for (const nlohmann::json& e : h) {
    EXPECT_NE(e["effect"], "thermal_drift_temp");
    if (e["minimal_detectable"].is_null()) continue;
    planned[e["effect"]] = e["minimal_detectable"].get<double>();
    largest_shift = std::max(largest_shift, e["max_shift_sigma"].get<double>());
  }
  EXPECT_GE(planned.size(), 5u);
  EXPECT_GT(largest_shift, 1.0);

  ASSERT_EQ(RunTriadcal("simulate " + sc + " -o " + Path("sim") + " --seed 4", Path("s.err")).status,
            0);
  ASSERT_EQ(RunTriadcal("diagnose " + Path("sim/run.yaml") + " -o " + Path("d.json"),
                        Path("d.err"))
                .status,
            0);
  const nlohmann::json d = nlohmann::json::parse(ReadFile(Path("d.json")));
  int compared = 0;
  for (const nlohmann::json& e : d["could_hide"]) {
    const auto it = planned.find(e["effect"].get<std::string>());
    if (it == planned.end() || e["minimal_detectable"].is_null()) continue;
    EXPECT_NEAR(e["minimal_detectable"].get<double>() / it->second, 1.0, 0.1) << it->first;
    ++compared;
  }
  EXPECT_GE(compared, 4);

  // A recorded run: diagnose's job, refused with one line and no output.
  const auto bad = RunTriadcal("observability " + Path("sim/run.yaml") + " --could-hide -o " +
                                   Path("out.json"),
                               Path("bad.err"));
  EXPECT_EQ(bad.status, 2);
  EXPECT_EQ(bad.err,
            "triadcal: error: --could-hide: needs a SCENARIO.yaml (a planned profile); for a "
            "recorded run, `diagnose` reports what could hide\n");
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

}  // namespace
}  // namespace triadcal

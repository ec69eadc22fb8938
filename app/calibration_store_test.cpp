#include "app/calibration_store.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "app/acceptance.h"
#include "core/model/errors.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

class CalibrationStoreTest : public testing_fixtures::TempDirTest {
 protected:
  void Put(const std::string& name, const std::string& text) {
    std::filesystem::create_directories(std::filesystem::path(Path(name)).parent_path());
    WriteText(name, text);
  }
};

TEST_F(CalibrationStoreTest, FoldersAreNeverReused) {
  const std::string dir = Path("cal");
  EXPECT_EQ(ClaimCalibrationFolder(dir, "A1", "2026-11-23"), "A1/2026-11-23");
  EXPECT_EQ(ClaimCalibrationFolder(dir, "A1", "2026-11-23"), "A1/2026-11-23_2");
  EXPECT_EQ(ClaimCalibrationFolder(dir, "A1", "2026-11-23"), "A1/2026-11-23_3");
  EXPECT_EQ(ClaimCalibrationFolder(dir, "A1", "2026-11-24"), "A1/2026-11-24");
  EXPECT_EQ(ClaimCalibrationFolder(dir, "B2", "2026-11-23"), "B2/2026-11-23");
}

TEST_F(CalibrationStoreTest, PreviousIsTheLatestConvergedOneBefore) {
  const std::string dir = Path("cal");
  Put("cal/A1/2026-11-01/calibration.json", "{\"converged\": true}");
  Put("cal/A1/2026-11-20/calibration.json", "{\"converged\": true}");
  Put("cal/A1/2026-11-20_2/calibration.json", "{\"converged\": true}");
  Put("cal/A1/2026-11-20_10/calibration.json", "{\"converged\": false}");
  Put("cal/A1/2026-11-22/notes.txt", "no calibration here");
  Put("cal/A1/2026-11-25/calibration.json", "{\"converged\": true}");
  Put("cal/A1/other/calibration.json", "{\"converged\": true}");
  // _10 sorts after _2 as a number, but did not converge.
  EXPECT_EQ(PreviousCalibration(dir, "A1", "A1/2026-11-23"), "A1/2026-11-20_2");
  EXPECT_EQ(PreviousCalibration(dir, "A1", "A1/2026-11-20_2"), "A1/2026-11-20");
  EXPECT_EQ(PreviousCalibration(dir, "A1", "A1/2026-11-01"), "");
  EXPECT_EQ(PreviousCalibration(dir, "B9", "B9/2026-11-01"), "");
}

TEST(CalibrationStore, ChangeInSigmaOfTwoIndependentCalibrations) {
  const nlohmann::json now = {{"Kx", {{"value", 171.0}, {"sigma", 0.3}, {"estimable", true}}},
                              {"Ky", {{"value", 175.0}, {"sigma", 0.3}, {"estimable", false}}},
                              {"W0x", {{"value", 1500.0}, {"sigma", 0.4}}}};
  const nlohmann::json before = {{"Kx", {{"value", 170.0}, {"sigma", 0.4}, {"estimable", true}}},
                                 {"Ky", {{"value", 170.0}, {"sigma", 0.3}}}};
  const nlohmann::json c = ChangeInSigma(now, before);
  ASSERT_EQ(c.size(), 1u);  // Ky held now, W0x not calibrated before
  EXPECT_DOUBLE_EQ(c["Kx"].get<double>(), 1.0 / 0.5);
}

TEST(Acceptance, EachViolatedLimitIsNamed) {
  const nlohmann::json params = {{"Kx", {{"value", 180.25}, {"sigma", 0.3}, {"unit", "mV/g"}}},
                                 {"W0x", {{"value", 1500.0}, {"sigma", 0.9}, {"unit", "mV"}}}};
  std::vector<ParameterLimit> limits = {{"Kx", 165.0, 178.0, 0.5},
                                        {"W0x", 1490.0, std::nullopt, 0.5},
                                        {"Kz", std::nullopt, 1.0, std::nullopt}};
  const std::vector<LimitViolation> v = CheckLimits(limits, params);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0].Text(), "Kx 180.25 > max 178 mV/g");
  EXPECT_EQ(v[1].Text(), "W0x sigma 0.9 > sigma_max 0.5 mV");
  EXPECT_EQ(v[2].Text(), "Kz not in the calibration");
  limits[0].max = 181.0;
  limits[1].sigma_max = 1.0;
  limits.pop_back();
  EXPECT_TRUE(CheckLimits(limits, params).empty());
  const std::vector<LimitViolation> low =
      CheckLimits({{"Kx", 181.0, std::nullopt, std::nullopt}}, params);
  ASSERT_EQ(low.size(), 1u);
  EXPECT_EQ(low[0].Text(), "Kx 180.25 < min 181 mV/g");
}

// A limit on a parameter the run did not determine (held: sigma null;
// considered: "determined": false) cannot be judged: named, never a crash or
// a pass; a change against a previous calibration skips it.
TEST(Acceptance, UndeterminedParameterIsNamedNotJudged) {
  const nlohmann::json params = {
      {"Kx", {{"value", 174.0}, {"sigma", nullptr}, {"unit", "mV/g"}, {"held", true}}},
      {"Ky", {{"value", 174.0}, {"sigma", 9.0}, {"unit", "mV/g"}, {"determined", false}}}};
  const std::vector<LimitViolation> v =
      CheckLimits({{"Kx", std::nullopt, 171.6, std::nullopt}, {"Ky", 170.0, std::nullopt, 1.0}},
                  params);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[0].Text(),
            "Kx not determined by this run (kept at nominal): its limits cannot be judged");
  EXPECT_EQ(v[1].limit, "not_determined");
  const nlohmann::json change = ChangeInSigma(params, params);
  EXPECT_FALSE(change.contains("Kx"));
}

TEST(CalibrationStore, DateMustBeIso) {
  CheckDate("2026-01-31");
  for (const char* bad : {"2026-1-31", "31.01.2026", "2026-13-01", "2026-01-31x"}) {
    try {
      CheckDate(bad);
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string("--date: expected YYYY-MM-DD, got '") + bad + "'");
    }
  }
}

}  // namespace
}  // namespace triadcal

// The settings of the fit job (app/fit_job.h): the option names both ways,
// one Validate naming the option, the defaults of `triadcal fit`.
#include "app/fit_job.h"

#include <gtest/gtest.h>

#include <string>

#include "core/model/errors.h"
#include "tests/error_of.h"

namespace triadcal {
namespace {

using testing_fixtures::ValidateError;

TEST(FitSettings, DefaultsAreThoseOfTheCommand) {
  const FitSettings s;
  EXPECT_EQ(s.init, FitInit::kRts);
  EXPECT_EQ(s.sigma, SigmaMethod::kAuto);
  EXPECT_EQ(s.epoch_s, kDefaultEpoch_s);
  EXPECT_EQ(s.rate_window_s, AngleDerivativeOptions().half_window_s);
  EXPECT_TRUE(s.auto_hold);
  EXPECT_EQ(ValidateError(s), "");
  const BatchOptions o = MakeBatchOptions(s);
  EXPECT_EQ(o.init, BatchInit::kRts);
  EXPECT_EQ(o.sigma, "auto");
  EXPECT_TRUE(o.holding.auto_hold);
}

TEST(FitSettings, NamesGoBothWays) {
  for (FitInit i : {FitInit::kRts, FitInit::kNominal}) EXPECT_EQ(ParseFitInit(FitInitName(i)), i);
  for (SigmaMethod m : {SigmaMethod::kAuto, SigmaMethod::kWhite, SigmaMethod::kHac}) {
    EXPECT_EQ(ParseSigmaMethod(SigmaMethodName(m)), m);
  }
  const std::vector<FitCheck> checks = ParseFitChecks("converged, white,noise,pass");
  ASSERT_EQ(checks.size(), 4u);
  EXPECT_EQ(checks[1], FitCheck::kWhite);
  EXPECT_EQ(std::string(FitCheckName(checks[3])), "pass");
}

TEST(FitSettings, BadTextNamesTheOption) {
  EXPECT_THROW(ParseFitInit("kalman"), InputError);
  try {
    ParseFitInit("kalman");
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "--init: expected rts or nominal, got 'kalman'");
  }
  try {
    ParseFitChecks("converged,fast");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--require: unknown check 'fast' (converged, white, noise, pass)");
  }
  try {
    ParseSigmaMethod("robust");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "--sigma: expected auto, white or hac, got 'robust'");
  }
}

TEST(FitSettings, ValidateNamesTheOption) {
  FitSettings s;
  s.effects = "no_such_effect";
  EXPECT_EQ(ValidateError(s).rfind("--effects: ", 0), 0u) << ValidateError(s);
  s = FitSettings();
  s.hold = {"Kx"};
  s.free = {"Kx"};
  EXPECT_EQ(ValidateError(s), "--hold/--free: 'Kx' given to both: hold it or free it");
  s = FitSettings();
  s.rate_window_s = 0.0;
  EXPECT_EQ(ValidateError(s).rfind("--rate-window-s: ", 0), 0u) << ValidateError(s);
  s = FitSettings();
  s.threads = -1;
  EXPECT_EQ(ValidateError(s), "--threads: Value -1 not in range 0 to 1024");
}

}  // namespace
}  // namespace triadcal

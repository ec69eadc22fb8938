// One run through the batch solver as `triadcal fit` does it: the settings,
// SolveBatch, and the OUT.json. `fit`, `batch`, Python (`triadcal.fit`) and
// the consumer example all call FitRun, so that a production calibration is
// the very file `fit` would write.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/fit_report.h"
#include "app/run_loading.h"
#include "app/session.h"
#include "core/model/angle_derivatives.h"
#include "core/model/parameters.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// Where the fit starts: the EKF + RTS smoother's estimate, or the nominal values.
enum class FitInit { kRts, kNominal };
// Which covariance gives sigma: HAC when the residuals are not white, the
// model's, or the sandwich robust to residuals correlated in time.
enum class SigmaMethod { kAuto, kWhite, kHac };
// A check a finished fit must pass (--require), else kExitRequirementFailed.
enum class FitCheck { kConverged, kWhite, kNoise, kPass };

// The names of the options ("rts", "auto", "converged"), and back. The
// parsers throw InputError naming the option, e.g. "--init: expected rts or
// nominal, got 'x'".
const char* FitInitName(FitInit init);
const char* SigmaMethodName(SigmaMethod sigma);
const char* FitCheckName(FitCheck check);
FitInit ParseFitInit(const std::string& text);
SigmaMethod ParseSigmaMethod(const std::string& text);
std::vector<FitCheck> ParseFitChecks(const std::string& list);  // "converged,white"

// The settings of a fit, each default declared here once.
struct FitSettings {
  std::string effects;  // catalogue effects to estimate too, "a,b"
  FitInit init = FitInit::kRts;
  SigmaMethod sigma = SigmaMethod::kAuto;
  double epoch_s = kDefaultEpoch_s;                               // [s]
  double rate_window_s = AngleDerivativeOptions().half_window_s;  // [s]
  int threads = 0;                                                // 0: all cores
  bool correlations = false;                                      // the correlation matrix in OUT
  // Hold what the run does not determine (structural nulls held, the others
  // kept at nominal and their prior uncertainty carried into sigma).
  bool auto_hold = true;
  std::vector<std::string> hold, free;  // parameter names
  std::vector<FitCheck> require;

  // Throws InputError naming the option (as the command line's flag) for a
  // bad setting, before any work.
  void Validate() const;
};

struct FitOutcome {
  ParameterLayout layout;
  BatchResult result;
  FitReport report;
  nlohmann::json json;  // OUT.json of `fit` (without the provenance its writer adds)
  // The fit's warnings (also said through the session): where it did not
  // start as asked (BatchResult::start_note), naming the run.
  std::vector<std::string> warnings;
};

// The batch solver's options of these settings (no progress set).
BatchOptions MakeBatchOptions(const FitSettings& s);

// Validates the settings and fits `run` (read from run_yaml); progress goes
// to the session's callbacks. The parameter units follow the readings.
FitOutcome FitRun(const FitSettings& s, const std::string& run_yaml, const LoadedRun& run,
                  const Session& session);

// The warning line when the declared noise is not what the residuals hold
// ("" when it is, or when the run asked for noise_mV: auto).
std::string NoiseWarning(const std::string& run_yaml, const LoadedRun& run, const BatchResult& r);

// The exit status of a finished fit: 0, kExitNotConverged, or
// kExitRequirementFailed for a required check that failed; *message says why.
int FitExitStatus(const FitSettings& s, const std::string& run_yaml, const BatchResult& r,
                  const FitReport& rep, std::string* message);

}  // namespace triadcal

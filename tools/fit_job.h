// One run through the batch solver as `triadcal fit` does it: the options,
// SolveBatch, and the OUT.json. `fit` and `batch` both call this, so that a
// production calibration is the very file `fit` would write.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "core/model/parameters.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/run_problem.h"
#include "tools/command_util.h"
#include "tools/report/fit_report.h"

namespace triadcal {

struct FitSettings {
  std::string effects, init = "rts";
  std::string sigma = "auto";  // auto | white | hac (BatchOptions::sigma)
  double epoch_s = kDefaultEpoch_s, rate_window_s = 0.1;
  int threads = 0;
  bool correlations = false, no_auto_hold = false;
  std::string hold, free;
  std::string require;  // checks that must hold: converged, white, noise, pass
};

struct FitOutcome {
  ParameterLayout layout;
  BatchResult result;
  FitReport report;
  nlohmann::json json;  // OUT.json of `fit`
};

// The batch solver's options of these settings (progress not set).
BatchOptions MakeBatchOptions(const FitSettings& s);

// Throws InputError for a bad setting (before any work).
void CheckFitSettings(const FitSettings& s);

// Fits `run` (read from run_yaml); progress lines go to `progress` (may be empty).
// fraction (may be empty) gets the fraction of the work done.
FitOutcome FitRun(const FitSettings& s, const std::string& run_yaml, const LoadedRun& run,
                  const std::function<void(const std::string&)>& progress,
                  const std::function<void(double)>& fraction = nullptr);

// The warning line when the declared noise is not what the residuals hold
// ("" when it is, or when the run asked for noise_mV: auto).
std::string NoiseWarning(const std::string& run_yaml, const LoadedRun& run, const BatchResult& r);

// The exit status of a finished fit: 0, kExitNotConverged, or
// kExitRequirementFailed for a --require check that failed; *message says why.
int FitExitStatus(const FitSettings& s, const std::string& run_yaml, const BatchResult& r,
                  const FitReport& rep, std::string* message);

// Registers the fit options shared by `fit` and `batch` on a subcommand.
void AddFitOptions(CLI::App* app, FitSettings* s);

}  // namespace triadcal

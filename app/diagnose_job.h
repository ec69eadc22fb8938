// The closed loop of SPEC section 8 on one run and its OUT.json, shared by
// `triadcal diagnose` and `triadcal batch` (manifest `diagnose: true`).
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "app/run_loading.h"
#include "app/session.h"
#include "solvers/diagnosis/effect_discovery.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// OUT.json of `diagnose` on `run`; `truth` (file units by parameter name) may be null.
nlohmann::json DiagnoseJson(const std::string& run_yaml, const LoadedRun& run, double alpha,
                            const DiagnosisResult& d, const std::map<std::string, double>* truth);

// The "could_hide" array of OUT (docs/file-formats.md), also written by
// `observability --could-hide`.
nlohmann::json CouldHideJson(const std::vector<HideCase>& could_hide);

// The settings of `diagnose`, each default declared here once.
struct DiagnoseSettings {
  std::string candidates;  // effects to test, "a,b" (empty: the whole catalogue)
  double alpha = 0.01;     // false-selection rate per round, in (0, 1)
  int max_effects = 4;     // at most this many effects, 0 .. 20
  double epoch_s = kDefaultEpoch_s;
  // Half window of the local cubic fit giving the bench rates (the latency's
  // rate among them) [s], as `fit`'s.
  double rate_window_s = AngleDerivativeOptions().half_window_s;
  int threads = 0;  // of the fits (0: all cores)

  // Throws InputError naming the option (as the command line's flag).
  void Validate() const;
};

struct DiagnoseOutcome {
  DiagnosisResult result;
  nlohmann::json json;  // OUT.json of `diagnose` (without the provenance)
  // Its warnings (also said through the session): where the declared model's
  // fit did not start as asked (BatchResult::start_note), naming the run.
  std::vector<std::string> warnings;
};

// Validates the settings and runs the closed loop on `run` (read from
// run_yaml); `truth` (file units by parameter name) may be null. Progress
// goes to the session's callbacks.
DiagnoseOutcome DiagnoseRun(const DiagnoseSettings& s, const std::string& run_yaml,
                            const LoadedRun& run, const std::map<std::string, double>* truth,
                            const Session& session);

}  // namespace triadcal

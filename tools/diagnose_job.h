// The closed loop of SPEC section 8 on one run and its OUT.json, shared by
// `triadcal diagnose` and `triadcal batch` (manifest `diagnose: true`).
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "solvers/diagnosis/effect_discovery.h"
#include "tools/command_util.h"

namespace triadcal {

// OUT.json of `diagnose`; `truth` (file units by parameter name) may be null.
nlohmann::json DiagnoseJson(const std::string& run_yaml, double alpha, const DiagnosisResult& d,
                            const std::map<std::string, double>* truth);

// The "could_hide" array of OUT (docs/file-formats.md), also written by
// `observability --could-hide`.
nlohmann::json CouldHideJson(const std::vector<HideCase>& could_hide);

// `diagnose` with its default settings (alpha 0.01, at most 4 effects, every
// candidate) at the given epoch interval and fit threads.
nlohmann::json DiagnoseRun(const std::string& run_yaml, const LoadedRun& run, double epoch_s,
                           int threads);

}  // namespace triadcal

// `triadcal design SCENARIO.yaml`: experiment design from the Cramer-Rao
// bound of the scenario's profile (solvers/analysis/design_study.h) -- sigma
// against duration for the profile and a static multi-position test, against
// periods and amplitudes, the shortest duration reaching each target, and the
// scenario's design against the static method. The settings, the study and
// the OUT.json; the command prints it (tools/report/design_report.h).
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/session.h"
#include "core/simulation/simulator.h"
#include "solvers/analysis/design_study.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// The settings of `design`, each default declared here once.
struct DesignSettings {
  std::string effects;  // catalogue effects to include, "a,b"
  std::vector<double> durations_s = {15, 30, 60, 90, 300, 600, 2400};  // [s], > 0
  // The profile grid, OUTER:INNER pairs; empty: the scenario's periods x 0.5,
  // 1, 2 and amplitudes x 0.25, 0.5, 1.
  std::vector<std::array<double, 2>> periods_s, amplitudes_deg;
  // Target sigma in file units of a parameter or group (K, W0, angles, K_ij,
  // bench, dR: the worst member); the study fills in the indices.
  std::vector<DesignTarget> targets = {{"K", 0.5, {}}};
  double design_duration_s = 0.0;     // of the grid and the comparison; 0: the scenario's
  double static_duration_s = 2400.0;  // of the static method in the comparison [s]
  int static_positions = 12;          // 6, 12 or 18
  double epoch_s = kDefaultEpoch_s;   // [s]
  int threads = 0;                    // 0: all cores

  // Throws InputError naming the option (as the command line's flag).
  void Validate() const;
};

// The command line's text forms, each throwing InputError naming `option`:
// "15,30,60" (positive numbers), "30:12,60:24" (OUTER:INNER pairs) and
// "K=0.5,W0=2" (--target NAME=SIGMA); and back (%g).
std::vector<double> ParsePositiveList(const std::string& text, const std::string& option);
std::vector<std::array<double, 2>> ParsePairs(const std::string& text, const std::string& option);
std::vector<DesignTarget> ParseDesignTargets(const std::string& text);
std::string ListText(const std::vector<double>& values);
std::string TargetsText(const std::vector<DesignTarget>& targets);

struct DesignOutcome {
  ParameterLayout layout;
  DesignStudyOptions options;  // as run: durations sorted, target indices filled
  DesignStudy study;
  double seconds = 0.0;
  nlohmann::json json;  // OUT.json of `design` (without the provenance)
};

// Validates the settings and runs the study of `s` (read from
// scenario_path); progress goes to the session's callbacks.
DesignOutcome DesignRun(const DesignSettings& settings, const std::string& scenario_path,
                        const Scenario& s, const Session& session);

}  // namespace triadcal

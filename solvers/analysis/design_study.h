// The design study of `triadcal design` (experiment_design.h does the single
// evaluations): for one scenario and layout,
//   1. sigma of every parameter against the run duration, for the scenario's
//      quasi-harmonic profile and for a static multi-position test of the same
//      total time;
//   2. sigma over a grid of profile periods x amplitudes at the design duration;
//   3. the scenario's design against the static method (its own duration and
//      the design duration);
//   4. the shortest duration of the profile that reaches each target sigma.
// The command (tools/cmd_design.cpp) parses the flags into DesignStudyOptions
// and reports the result (tools/report/design_report.h).
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "core/simulation/simulator.h"
#include "solvers/analysis/experiment_design.h"

namespace triadcal {

// A target: the worst sigma of `indices` (a parameter or a group) at most
// sigma_file (file units of the first member).
struct DesignTarget {
  std::string key;
  double sigma_file = 0.0;
  std::vector<int> indices;
};

struct DesignStudyOptions {
  std::vector<double> durations_s;  // ascending, not empty
  // Profile grid: periods OUTER:INNER [s] and amplitudes OUTER:INNER [deg];
  // empty: the scenario's x 0.5, 1, 2 and x 0.25, 0.5, 1.
  std::vector<std::array<double, 2>> periods_s, amplitudes_deg;
  std::vector<DesignTarget> targets;
  double design_duration_s = 0.0;  // 0: the scenario's
  double static_duration_s = 2400.0;
  int static_positions = 12;  // 6, 12 or 18 (StaticPositions)
  DesignOptions design;       // epoch_s, derivatives, observability
  // Called before each step with what it does and the fraction done.
  std::function<void(const std::string&, double)> progress;
};

struct DesignGridPoint {
  std::array<double, 2> period_s, amplitude_deg;
  DesignPoint d;
};

struct DesignStudy {
  std::vector<double> durations_s;
  std::vector<std::array<double, 2>> positions;  // static orientations [rad]
  double design_duration_s = 0.0, static_duration_s = 0.0;
  std::vector<DesignPoint> quasi_harmonic, static_test;  // per duration
  std::vector<DesignGridPoint> grid;
  DesignPoint qh_design;                          // the profile at the design duration
  DesignPoint static_long;                        // static test, static_duration_s
  DesignPoint static_design;                      // static test, design duration
  std::vector<TargetResult> targets;              // per options.targets
  double target_min_s = 0.0, target_max_s = 0.0;  // the bisection's range
};

// Throws OptionError (errors.h) naming the DesignStudyOptions field for a bad
// setting: static_duration_s <= 0, durations_s whose longest has more samples
// than a simulation may hold, static_positions not 6, 12 or 18.
DesignStudy RunDesignStudy(const Scenario& s, const ParameterLayout& layout,
                           const DesignStudyOptions& options);

// Summaries of a design point over parameter indices (SI).
double WorstSigma(const DesignPoint& d, const std::vector<int>& indices);
// True when the design does not determine the parameter (its sigma is the prior's).
bool Undetermined(const DesignPoint& d, const std::string& name);
bool AnyUndetermined(const DesignPoint& d, const ParameterLayout& layout,
                     const std::vector<int>& indices);

// Least-squares slope of log sigma against log T over the points with
// T >= t_from and a finite positive sigma; NaN with fewer than 2 points.
double LogSlope(const std::vector<double>& T, const std::vector<double>& sigma, double t_from);

}  // namespace triadcal

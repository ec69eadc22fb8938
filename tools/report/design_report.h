// Reports of the design study (solvers/analysis/design_study.h): OUT.json,
// the log-log SVG plot of sigma against duration, and the tables on stdout.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "core/simulation/simulator.h"
#include "solvers/analysis/design_study.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// What the report says about how the study was asked for.
struct DesignReportSettings {
  std::string scenario_path;
  std::string effects;  // as given, "a,b"
  double epoch_s = kDefaultEpoch_s;
  int static_positions = 12;
};

// OUT.json of `design` (without "plot" and "time_s", which the command adds).
nlohmann::json DesignJson(const Scenario& s, const ParameterLayout& layout,
                          const DesignStudyOptions& options, const DesignStudy& r,
                          const DesignReportSettings& settings);

// The tables on stdout, up to the comparison's footnote.
void PrintDesign(const Scenario& s, const ParameterLayout& layout,
                 const DesignStudyOptions& options, const DesignStudy& r,
                 const DesignReportSettings& settings);

}  // namespace triadcal

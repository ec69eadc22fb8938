// What `fit` and `compare` say about a batch solution: the verdict line, the
// parameters the run cannot separate or that sit at their prior, the JSON and
// the printed table.
#pragma once

#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/separability.h"

namespace triadcal {

struct FitReport {
  std::vector<WeakDirection> weak;
  std::set<std::string> not_estimable;      // held, or in a weak direction
  std::set<std::string> held;
  std::vector<std::string> at_prior_bound;  // > 3 prior sigma from the nominal value
  std::string verdict;
};

FitReport MakeFitReport(const ParameterLayout& layout, const BatchResult& r);
nlohmann::json FitJson(const ParameterLayout& layout, const BatchResult& r, const FitReport& rep,
                       bool correlations);
void PrintParameterTable(const ParameterLayout& layout, const BatchResult& r, const FitReport& rep);
std::string ResidualsCsv(const BatchResult& r);

}  // namespace triadcal

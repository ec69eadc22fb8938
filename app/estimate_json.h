// The "parameters" object of every OUT file (docs/file-formats.md):
//   {"Kx": {"value": 171.52, "sigma": 0.08, "unit": "mV/g"}, ...}
// values and sigmas in file units; "estimable": false marks parameters that the
// run cannot separate (their value is the prior's).
#pragma once

#include <map>
#include <set>
#include <string>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/model/parameters.h"
#include "solvers/estimation/separability.h"

namespace triadcal {

nlohmann::json ParametersJson(const ParameterLayout& layout, const Eigen::VectorXd& theta,
                              const Eigen::MatrixXd& cov,
                              const std::set<std::string>& not_estimable);

// Marks each parameter estimated only relative to held ones:
// "relative_to": [held names], "estimable": false.
void MarkRelative(const std::map<std::string, std::vector<std::string>>& relative_to,
                  nlohmann::json* parameters);

nlohmann::json WeakDirectionsJson(const std::vector<WeakDirection>& dirs);

// Correlation matrix {"names": [...], "matrix": [[...]]}.
nlohmann::json CorrelationJson(const ParameterLayout& layout, const Eigen::MatrixXd& cov);

}  // namespace triadcal

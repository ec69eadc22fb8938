// Monte Carlo runs as JSON that reads back bit for bit, so that MPI ranks and
// Slurm shards can hand their runs to the one place that sums them in seed
// order (SummariseMonteCarlo). Finite doubles are written as the shortest
// decimal that reads back to the same double (nlohmann::json does this);
// NaN (a parameter held in that run) and infinities as the strings "nan",
// "inf", "-inf".
//
//   [{"seed": 7, "truth": [...], "estimators": [{"error": [...], "sigma": [...],
//     "failure": ""}, ...]}, ...]        values in SI, in layout order
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solvers/analysis/monte_carlo.h"

namespace triadcal {

nlohmann::json MonteCarloRunsJson(const std::vector<MonteCarloRun>& runs);

// Throws InputError("WHERE: records: ...") when `j` is not what
// MonteCarloRunsJson writes for `estimators` estimators of `parameters` values.
std::vector<MonteCarloRun> MonteCarloRunsFromJson(const nlohmann::json& j, std::size_t estimators,
                                                  int parameters, const std::string& where);

// One double / vector the same way (also for the truth and CRB of a shard).
nlohmann::json ExactJson(double x);
nlohmann::json ExactJson(const Eigen::VectorXd& v);
Eigen::VectorXd ExactVector(const nlohmann::json& j, int size, const std::string& where);

}  // namespace triadcal

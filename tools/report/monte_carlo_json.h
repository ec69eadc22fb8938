// The OUT.json and the printed table of `triadcal montecarlo`, written from a
// MonteCarloResult; shared by the command and by `triadcal merge`, so that
// shards merged give the very file one process gives.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solvers/analysis/monte_carlo.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// What the command was asked (and the scenario's rate and duration).
struct MonteCarloSettings {
  std::string scenario, effects;
  std::vector<std::string> estimators;
  int runs = 0;
  std::uint64_t first_seed = 1;
  double epoch_s = kDefaultEpoch_s, tolerance = 0.1, rate_hz = 0.0, duration_s = 0.0;
  bool per_seed = false;
  bool gyro = false;  // the layout has the gyro block (the scenario has a gyro)
};

nlohmann::json MonteCarloSettingsJson(const MonteCarloSettings& s);
// Throws InputError("WHERE: settings: ...") on a missing or mistyped key.
MonteCarloSettings MonteCarloSettingsFromJson(const nlohmann::json& j, const std::string& where);

// OUT.json; r.runs must hold the runs when s.per_seed.
nlohmann::json MonteCarloJson(const MonteCarloSettings& s, const MonteCarloResult& r);

// The table on stdout (from the JSON's checks).
void PrintMonteCarlo(const MonteCarloSettings& s, const MonteCarloResult& r,
                     const nlohmann::json& out);

}  // namespace triadcal

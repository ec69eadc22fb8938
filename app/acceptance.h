// Acceptance of one calibration against the manifest's limits: each limit on
// a parameter's value (min, max) or on its sigma (sigma_max), read from the
// "parameters" object of the calibration (SPEC section 7) in the unit that
// object gives the parameter: the fit's, which follows the readings (counts/g
// for readings in counts, mV/g for mV), never an assumed mV.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/manifest.h"

namespace triadcal {

struct LimitViolation {
  std::string parameter;
  std::string limit;   // "min", "max", "sigma_max", or "missing" (not in the calibration)
  double value = 0.0;  // the value, or the sigma for sigma_max
  double bound = 0.0;  // the limit
  std::string unit;
  // "Kx 180.3 > max 178 mV/g"
  std::string Text() const;
};

std::vector<LimitViolation> CheckLimits(const std::vector<ParameterLimit>& limits,
                                        const nlohmann::json& parameters);

// The limits as unit.json lists them: [{"parameter", "min", "max", "sigma_max"}]
// (only the limits given).
nlohmann::json LimitsJson(const std::vector<ParameterLimit>& limits);

nlohmann::json ViolationJson(const LimitViolation& v);
LimitViolation ViolationFromJson(const nlohmann::json& j);

}  // namespace triadcal

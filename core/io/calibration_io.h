// Reading a calibration (the parameters of an OUT or truth file).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "core/model/apply_calibration.h"

namespace triadcal {

// Reads the parameters of an OUT file of `fit` or `static` ("parameters"),
// `filter` ("rts" section), `compare` ("batch" section), or a truth.json
// (plain values). Each entry is {"value": v, "unit": u, ...} with u the unit of
// docs/file-formats.md, or a plain number in that unit. Effect parameters
// ("thermal_drift.rate_x", or "...rate_x_mV_per_min" as in truth.json) switch
// their effect on. The 21 sensor parameters (Kx..Kzz) are required; the bench
// and lever-arm parameters are not used. Throws InputError
// "PATH: parameters.NAME: what is wrong".
Calibration LoadCalibration(const std::string& path);

// The same from JSON already read; `path` names it in messages.
Calibration CalibrationFromJson(const nlohmann::json& root, const std::string& path);

}  // namespace triadcal

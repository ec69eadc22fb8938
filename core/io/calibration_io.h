// Reading a calibration (the parameters of an OUT or truth file).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "core/model/apply_calibration.h"
#include "core/model/run_description.h"

namespace triadcal {

// Reads the parameters of an OUT file of `fit`, `static` or `diagnose`
// ("parameters"), `filter` ("rts" section), `compare` ("batch" section), or a
// truth.json (plain values, no "command"). The OUT of any other command
// (observability's "parameters" are nominal values) is refused: "PATH: command
// 'observability': not a calibration (expected ...)". Each entry is {"value": v, "unit": u, ...} with u the unit of
// docs/file-formats.md, or a plain number in that unit. Effect parameters
// ("thermal_drift.rate_x", or "...rate_x_mV_per_min" as in truth.json) switch
// their effect on. The 21 sensor parameters (Kx..Kzz) are required; the bench
// and lever-arm parameters are not used. The gyro's 21 (gyro.Kx..gyro.Gzz,
// SPEC section 10) are all or none: given, the layout has the gyro block
// (ParameterLayout::has_gyro) with their values; absent, it has none. Throws
// InputError "PATH: parameters.NAME: what is wrong".
Calibration LoadCalibration(const std::string& path);

// The same from JSON already read; `path` names it in messages.
Calibration CalibrationFromJson(const nlohmann::json& root, const std::string& path);

// A calibration is validated like run.yaml: scale factors > 0 and within
// [1e-3, 1e8] per g, |bias| <= 1000 g worth of the scale, misalignment angles
// within 30 deg, |K_ij| <= 10 /g; gyro scale factors not 0 (either sign, as
// run.yaml's gyro.scale), gyro angles within 30 deg; no key given twice; no
// effect parameter
// this build does not know (bogus.tau: applying without it would be silently
// wrong), and in an OUT file (with a "command") no unknown parameter at all
// (a truth.json may hold other plain keys, SPEC section 7); one readings unit
// for all entries. Bounds of PlausibilityBounds and CalibrationBounds below.
struct CalibrationBounds {
  static constexpr double kMaxAngle_arcmin = 1800.0;  // 30 deg
  static constexpr double kMaxNonlinearity_per_g = 10.0;
  static constexpr double kMaxScaleRatio = 10.0;  // against the run's nominal scale
};

// Before applying `cal` to a run: its readings unit must be the run's
// (a calibration in mg/g on readings in mV is wrong by the ratio of the
// scales), and each scale factor within a factor 10 of the run's nominal
// scale (0.1715 "mV/g" is V/g); with a gyro in both, each |gyro.K_i| within a
// factor 10 of the run's |gyro.scale_i| (57.3: rad/s for deg/s). Throws
// InputError "CAL: parameters.Kx: ...".
void CheckCalibrationForRun(const Calibration& cal, const RunDescription& run);

}  // namespace triadcal

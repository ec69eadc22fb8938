// Results far outside what the hardware can have: a warning naming the
// likely cause, in the tools layer, on the "parameters" of an OUT file. A fit
// can converge "perfectly" onto nonsense when the input hides a systematic
// error the model absorbs: an inner angle-sensor zero 5 deg off under the
// levelling constraint dpsi - dlambda2 = 0 came out as gamma_y = 442 arcmin
// (7.4 deg) with the verdict "pass".
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace triadcal {

// Bounds (file units) beyond which a result is implausible.
struct ResultBounds {
  // A MEMS triad's axes are within about 1 deg of its case (the paper's chip,
  // mounted in its IMU, had 2 deg 20'); 3 deg is beyond any. An angle-sensor
  // zero 5 deg off moves a pair of angles by 5 deg.
  static constexpr double kMaxMisalignment_arcmin = 180.0;
  // A bench is levelled, and its angle sensors zeroed, to arcminutes; 5 deg
  // is an angle-sensor zero or an angle unit.
  static constexpr double kMaxBenchAngle_arcmin = 300.0;
  // The lever-arm error against the drawings' R0 (the prior's sigma is 50 mm).
  static constexpr double kMaxLeverArmError_mm = 150.0;
};

// One warning line per implausible parameter of `parameters` ({"NAME":
// {"value": v, "unit": u, ...}} as every OUT writes them): "WHERE:
// parameters.gamma_y = 442 arcmin (7.37 deg) is beyond what a triad's axes
// can be off (3 deg): likely ...". Parameters not estimated ("held", or
// "estimable": false) are not judged.
std::vector<std::string> ImplausibleResultWarnings(const nlohmann::json& parameters,
                                                   const std::string& where);

}  // namespace triadcal

// Units and constants. Inside triadcal everything is SI (m, s, rad, m/s^2),
// except the two quantities of the readings model (paper eq. 1) that have no SI
// counterpart: readings are in mV and the specific force W is dimensionless,
// expressed in units of g (so scale factors are mV/g and K_ij are 1/g).
// Conversions to the units of the files (docs/file-formats.md) happen only at the
// file boundary, through the tables in parameters.h and effects.h.
#pragma once

namespace triadcal {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kArcminToRad = kPi / (180.0 * 60.0);
constexpr double kArcsecToRad = kPi / (180.0 * 3600.0);
constexpr double kMmToM = 1e-3;
constexpr double kMsToS = 1e-3;
constexpr double kStandardGravity = 9.80665;  // m/s^2, docs/method.md default

}  // namespace triadcal

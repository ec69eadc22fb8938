// `triadcal export`: a calibration in forms other programs use.
//
//   c            a dependency-free C99 header and source applying the
//                calibration: raw readings (in the unit of the readings it
//                was estimated from) -> specific force W [g], the exact
//                inverse of the readings model (paper eq. 1) with the same
//                Newton iteration as bench_model.h SpecificForceFromReadings_g,
//                including the sensor-stage effects (thermal_drift,
//                thermal_drift_temp, scale_asymmetry, cross_quadratic). Geometry and angle
//                effects do not act on W and are left out, as in `apply`.
//                With the gyro (SPEC section 10) a second function applies
//                it: gyro readings [deg/s] and W [g] -> angular rate [deg/s],
//                including the gyro-stage effects (gyro_scale_asymmetry,
//                gyro_nonlinearity) with the same Newton steps as gyro_model.h
//                GyroAxisRate.
//   yaml, json   the plain matrix form (MatrixForm below).
//
// Every sensor- and gyro-stage effect of the catalogue that `apply` inverts is either
// carried by every exported form or refused (ExportRefusal below): a form that
// left one out would differ from `apply` without saying so.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "core/model/apply_calibration.h"
#include "core/model/effects.h"

namespace triadcal {

struct CExport {
  std::string header;  // FILE.h
  std::string source;  // FILE.c (includes "FILE.h")
};

// C99 code for the calibration; `name` prefixes the function (a C
// identifier); `file_base` is the base of the file names, FILE.h and FILE.c
// (default: name), so that the source includes the header under the name it
// is written with (`export --name NAME -o OTHER.c`); `comment` goes into both
// files' heading (e.g. the provenance), one line per line.
// Throws InputError when `cal` has an effect the exported forms do not carry.
CExport ExportC(const Calibration& cal, const std::string& name, const std::string& comment,
                const std::string& file_base = "");

// Whether the exported forms carry a sensor-stage effect of the catalogue: the
// zero-offset effects whose signal the C function's arguments give (t_s:
// thermal_drift; temp_C - temp_ref_C: thermal_drift_temp), scale_asymmetry and
// cross_quadratic; and the gyro-stage effects that change the gyro's per-axis
// response (gyro_scale_asymmetry, gyro_nonlinearity). Not carried:
// thermal_drift_quadratic, whose signal is defined over the span of the run it
// is applied to (firmware has no run).
// Geometry and angle effects do not act on W: true (left out, as in `apply`).
bool ExportCarries(const EffectSpec& effect);

// "" when every effect of `cal` is carried, else the one-line reason naming
// the first effect that is not ("CAL: thermal_drift_quadratic: ...").
std::string ExportRefusal(const Calibration& cal);

// The readings model as matrices, in SI and in g (g0 = 9.80665 m/s^2):
//
//   z = S a + b + diag(a) N a          z readings [U], a specific force
//                                      [m/s^2] in the triad frame
//   S = diag(K) M / g0                 scale-misalignment [U per m/s^2]
//   N = diag(K) Kij / g0^2             nonlinearity [U per (m/s^2)^2]
//   b = W0                             bias [U]
//
// U is the unit of the readings the calibration was estimated from
// (cal.readings_unit: mV, mg or counts; mV when the file names none, as a
// truth.json): "readings_unit" holds it and the keys name it (S_U_per_mps2,
// b_U, ...), as do the C code's comments and its argument z_U.
// Plus S^-1 (the linear inverse) and the sensor-stage effects' parameters;
// with the gyro, "gyro":
//
//   g = S_g w + b_g + G W              g readings, w rate [deg/s], W [g]
//   S_g = diag(K_g) Mg                 [1]; S_inverse = Mg^-1 diag(K_g)^-1,
//   b_g = W0_g [deg/s], G [(deg/s)/g]  the correction w = S_g^-1 (g - b_g - G W)
//
// and with the gyro-stage effects "effects_model", "K", "Mg_inverse" and
// "effects" (each effect of the catalogue by name: its description and its
// parameters {"value", "unit"} in file units):
//
//   g_i = f_i((Mg w)_i) + b_i + (G W)_i,  f_i(m) = K_i m (1 + k2_i m^2) + dK_i |m|
//
// Throws InputError when `cal` has an effect the exported forms do not carry.
nlohmann::ordered_json MatrixForm(const Calibration& cal);

}  // namespace triadcal

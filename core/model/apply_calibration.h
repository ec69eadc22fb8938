// Applying a calibration: raw readings -> calibrated specific force.
//
// Convention. The forward model is the readings model of paper eq. 1
// (bench_model.h Readings_mV): specific force W [g, triad frame] -> readings
// [mV]. A calibration is its parameters theta (docs/file-formats.md); applying it is
// the exact inverse of that model, bench_model.h SpecificForceFromReadings_g:
//
//   u_i = (Wpr_i - W0_i) / K_i,    M W + diag(W) K W = u    (solved by Newton)
//
// so Readings_mV(theta, ApplyCalibration(theta, z)) = z to rounding. Sensor-
// stage effects of the calibration (thermal_drift, thermal_drift_temp,
// scale_asymmetry) are inverted with it; the drifts count from the start of the
// run they are applied to (t of its samples, its first temp_C), as in the
// estimators. Geometry and angle effects do not act on W at the sensing point
// and are ignored (size_effect: W is the one at the x accelerometer's point).
//
// The gyro (SPEC section 10), when the calibration has it: its readings model
// (gyro_model.h GyroReadings) inverted exactly, gyro_model.h
// GyroRateFromReadings,
//
//   w = Mg^-1 diag(K)^-1 (G - W0 - G_ij W)
//
// with W the corrected specific force of the same sample (above): the angular
// rate the gyro senses, in the triad frame (Earth's rate included).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/parameters.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

struct Calibration {
  std::string path;
  std::string section;  // where the parameters were: "parameters", "rts.parameters", ...
  std::string command;  // the "command" of the OUT file, or ""
  ParameterLayout layout;
  Eigen::VectorXd theta;  // SI
  // The unit of the readings it was estimated from ("mV", "mg" or "counts"),
  // as its entries' units say; "" when no entry gave a unit (truth.json).
  std::string readings_unit;
  // A joint fit of several runs (docs/multi-run.md) gives the triad in the
  // IMU's own axes ("axes": "imu"): applied through the run's mounting
  // (core/model/mounting.h). Other calibrations are in the axes of the run
  // they came from, as the readings after its mounting.
  bool imu_axes = false;
  // Temperature model: theta_i(T) = theta_i + sum_k c_ik (T - reference)^k,
  // T the sample's temp_C, else the run's temperature_C.
  double temperature_ref_C = 0.0;
  struct TemperatureTerm {
    int index;                  // in the layout
    std::vector<double> coefficients;  // SI per degC^k, k = 1, 2, ...
  };
  std::vector<TemperatureTerm> temperature_terms;
};

// W [g] in the triad frame of every sample of the run, by the exact inverse of
// the readings model with the calibration's parameters. Throws InputError when
// the calibration has a temperature model and the run no temperature.
std::vector<Eigen::Vector3d> ApplyCalibration(const Calibration& cal, const RunDescription& run,
                                              const RunData& data);

// The angular rate [rad/s] in the triad frame of every sample of the run from
// its gyro readings (RunData::gyro_rad_s) and W_g, the specific force [g] that
// ApplyCalibration gives for the same samples. Throws InputError when the
// calibration has no gyro block (cal.layout.has_gyro()), the run no gyro
// readings, or W_g another number of samples.
std::vector<Eigen::Vector3d> ApplyGyroCalibration(const Calibration& cal, const RunDescription& run,
                                                  const RunData& data,
                                                  const std::vector<Eigen::Vector3d>& W_g);

}  // namespace triadcal

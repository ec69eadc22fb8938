// The plausibility layer between reading and solving: every number that
// reaches the model is finite and inside a physical bound, and units that look
// wrong are recognised from the data. Each bound and its reason is listed in
// docs/input-validation.md; a violation is one InputError line naming the file,
// the line or key, and the bound.
//
// Two entry points: the run description as parsed (run.yaml, or the `run:`
// section of a scenario) and the run data as read (after the column mapping and
// the removal of repeated time stamps, before the angles are unwrapped).
#pragma once

#include <string>
#include <vector>

#include "core/io/data_table.h"
#include "core/io/run_validation.h"
#include "core/model/run_description.h"

namespace triadcal {

// Bounds (file units). See docs/input-validation.md for the reasons.
struct PlausibilityBounds {
  static constexpr double kMaxLeverArm_mm = 2000.0;
  static constexpr double kMaxAngleNoise_arcsec = 3600.0;
  static constexpr double kMinG_mps2 = 9.7;
  static constexpr double kMaxG_mps2 = 9.9;
  static constexpr double kMinScale = 1e-3;  // readings unit per g
  static constexpr double kMaxScale = 1e8;
  static constexpr double kMaxBiasInG = 1000.0;  // |bias| / scale
  static constexpr double kMinNoiseInG = 1e-7;   // noise / scale
  static constexpr double kMaxNoiseInG = 1.0;
  static constexpr double kPriorRatio = 1e6;           // override vs default sigma
  static constexpr double kMinConstraintRatio = 1e-6;  // sigma vs its prior scale
  static constexpr double kMaxConstraintValue = 1e3;   // |value| in prior scales
  static constexpr double kMaxAbsTime_s = 1e11;
  static constexpr double kMaxSpan_s = 1e6;
  static constexpr double kMaxMedianInterval_s = 0.5;
  static constexpr double kMinMedianInterval_s = 2e-5;
  static constexpr double kMaxAbsAngle_deg = 1e7;
  static constexpr double kMaxRate_deg_s = 3600.0;
  static constexpr double kMaxReadingInG = 1000.0;  // |reading - bias| / scale
  // The gyro's unit against the bench's angle rate (CheckGyroUnits).
  static constexpr double kGyroWindow_s = 0.1;             // angle differencing window
  static constexpr double kGyroMaxWindow_s = 1.0;          // longer: a gap, left out
  static constexpr double kGyroMinBenchRate_deg_s = 5.0;   // RMS; below: not judged
  static constexpr double kGyroUnitFactorTolerance = 4.0;  // around 57.3 (rad vs deg)
  static constexpr double kGyroMaxRatio = 5.0;             // RMS|g| / (|scale| RMS bench rate)
};

// The run description: bench, triad, priors and constraints. `where` is the
// file (or "file: run") used by the parser for its messages.
void CheckDescriptionPlausible(const RunDescription& run, const std::string& where);

// The samples as read, in our units (t s, angles deg, rates deg/s, readings
// in the readings unit on the IMU's own axes). Angles not yet unwrapped.
// nominal_scale and nominal_bias are per IMU axis (before mounting).
struct ChannelSet {
  const ChannelValues* t;
  const ChannelValues* lambda[2];
  const ChannelValues* w[3];
  const ChannelValues* rate[2];
};
void CheckSamplesPlausible(const DataTable& table, const ChannelSet& c,
                           const double (&nominal_scale)[3], const double (&nominal_bias)[3]);

// After unwrapping: the recorded angles change by no more than the rate bound
// between samples (catches one wild angle, or time in seconds declared as ms).
void CheckAngleRates(const DataTable& table, const ChannelValues& t,
                     const ChannelValues (&lambda)[2]);

// Long runs with the angles in radians: in windows where the angles (read as
// degrees) move by under 6 deg, gravity cannot turn by more than 0.1 g, yet the
// readings swing by more than 0.5 g in most of them.
void CheckAnglesNotRadiansWindowed(const DataTable& table, const ChannelValues (&lambda)[2],
                                   const ChannelValues (&w)[3], const double (&nominal_scale)[3],
                                   double nominal_noise);

// The gyro's unit, judged by the bench (SPEC section 10): over windows of
// about 0.1 s the recorded angles (unwrapped, deg) give the bench's rate,
// |omega| = sqrt(lambda1'^2 + lambda2'^2) whatever the axes, and the RMS of
// |g| over the run (g: gx gy gz in deg/s as declared, before mounting) is
// about |nominal_scale| times its RMS (biases and Earth's rate are small
// beside a bench moving at an RMS of more than 5 deg/s; below that nothing is
// judged). 57 times smaller with deg/s declared: rad/s declared as deg/s; 57
// times larger with rad/s declared: deg/s declared as rad/s (each within a
// factor 4 of 57.3); any other ratio beyond a factor 5: a wrong unit or
// count scale. Each one InputError line. declared_unit: the unit common to
// gx gy gz, empty when they differ.
void CheckGyroUnits(const DataTable& table, const ChannelValues& t,
                    const ChannelValues (&lambda)[2], const ChannelValues (&g)[3],
                    const std::string& declared_unit, double nominal_scale);

// Channels read from the file (not declared constant) that never change where
// motion is expected: both angles constant is an error (no bench motion; a run
// without a bench declares them with {value: ...}). One angle constant while
// the other moves, or a reading constant (a dead channel, a damaged file, or a
// bench that never moved), is a warning (returned, one line each).
std::vector<std::string> CheckConstantChannels(const DataTable& table,
                                               const ChannelValues (&lambda)[2],
                                               const bool (&lambda_from_file)[2],
                                               const ChannelValues (&w)[3],
                                               const bool (&w_from_file)[3]);

}  // namespace triadcal

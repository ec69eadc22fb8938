// `triadcal apply CALIBRATION.json RUN.yaml`: raw readings -> calibrated
// specific force [g] in the triad frame, by the exact inverse of the readings
// model (core/model/apply_calibration.h), and, when both the calibration and
// the run have the gyro (SPEC section 10), gyro readings -> angular rate
// [deg/s] in the triad frame. The job gives the CSV's text and the warnings;
// the command writes and prints them. It has no settings: the calibration
// and the run say everything.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "app/session.h"
#include "core/io/calibration_io.h"

namespace triadcal {

// The corrected specific force of a run on a bench (or held still) has |W|
// near 1 g: the dynamic terms of a bench add < 0.03 g. A median off by more
// than this says the calibration does not fit the run (a warning).
constexpr double kMaxMedianNormError_g = 0.1;

struct ApplyOutcome {
  Calibration calibration;
  std::size_t samples = 0;
  bool gyro = false;                         // the gyro corrected too
  std::vector<Eigen::Vector3d> W_g;          // specific force in the triad frame [g]
  std::vector<Eigen::Vector3d> omega_rad_s;  // angular rate in the triad frame; empty without gyro
  // One sentence each: only one of the calibration and the run has the gyro;
  // |W| far from 1 g.
  std::vector<std::string> warnings;
  std::string csv;  // t, Wx, Wy, Wz [, omega_*] [, lambda*] [, label], provenance in its heading
};

// Loads the calibration and the run (both recorded in the session's
// provenance), checks that the calibration suits the run
// (CheckCalibrationForRun) and applies it. Throws InputError naming the file.
ApplyOutcome ApplyRun(const std::string& calibration_json, const std::string& run_yaml,
                      Session* session);

}  // namespace triadcal

// One recorded run, in memory: time, recorded bench angles, readings, and the
// optional rate and temperature channels. Everything SI/radians except the
// readings (mV). Angles are unwrapped. Readings are already in the platform
// frame (the IMU mounting of run.yaml applied).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace triadcal {

struct RunData {
  std::vector<double> t_s;
  std::vector<double> lambda_rad[2];    // recorded lambda1, lambda2 (unwrapped)
  std::vector<double> rate_rad_s[2];    // recorded rates, empty when not in the file
  std::vector<double> w_mV[3];          // readings wx, wy, wz
  // gyro readings gx, gy, gz converted to rad/s (platform frame, like w_mV),
  // empty when the run has no gyro triad (SPEC section 10)
  std::vector<double> gyro_rad_s[3];
  // per sample: 1 where a gyro channel is held at its range's limit (clipped),
  // empty when none is
  std::vector<char> gyro_clipped;
  std::vector<double> temp_C;           // empty when not in the file
  std::vector<std::string> label;       // per-sample position label (columns.label), or empty

  std::size_t size() const { return t_s.size(); }
  bool has_rates() const { return !rate_rad_s[0].empty(); }
  bool has_temp() const { return !temp_C.empty(); }
  bool has_gyro() const { return !gyro_rad_s[0].empty(); }
  Eigen::Vector3d gyro(std::size_t k) const {
    return {gyro_rad_s[0][k], gyro_rad_s[1][k], gyro_rad_s[2][k]};
  }
  bool has_label() const { return !label.empty(); }
  Eigen::Vector3d readings_mV(std::size_t k) const {
    return {w_mV[0][k], w_mV[1][k], w_mV[2][k]};
  }
};

// What validation found that is worth telling but not fatal ("12 duplicate time
// stamps dropped"); each is one line for stderr.
struct RunWarnings {
  std::vector<std::string> lines;
};

}  // namespace triadcal

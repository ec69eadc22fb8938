// The run description (run.yaml, docs/file-formats.md): where the data are, what the
// bench and the triad are nominally, the constraints (pseudo-measurements), and
// for files other than the CSV contract, how their columns map to ours and how
// the IMU sits on the platform.
//
//   data: run.csv                       # relative to this file
//   bench:
//     lever_arm_mm: [138, 20, 20]       # R0
//     angle_noise_arcsec: 15            # 1 sigma white noise of the recorded angles
//     g_mps2: 9.80665                   # optional
//     latitude_deg: 48.1                # optional, with heading_deg: Earth's rate
//     heading_deg: 0                    # in the gyro's input rate
//   triad:
//     scale_mV_per_g: [174, 174, 174]
//     bias_mV: [1500, 1500, 1500]
//     noise_mV: 2.0
//   gyro:           # optional: the IMU's gyro triad (columns gx, gy, gz)
//     scale: [1, 1, 1]
//     bias_dps: [0, 0, 0]
//     noise_dps: 0.05
//   constraints:
//     - {expr: "dpsi - dlambda2", value_arcmin: 0, sigma_arcsec: 30}
//   columns:        # optional; see docs/file-formats.md for the full mapping syntax
//   mounting:       # optional; axes: ["+x", "+y", "+z"]
//   sensor:         # optional; {serial: "SN 0042", model: "ADXL325"}
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/model/bench_model.h"
#include "core/model/parameters.h"
#include "core/model/run_data.h"

namespace triadcal {

// A linear pseudo-measurement sum_j coef_j theta_j = value +- sigma, all SI.
struct Constraint {
  std::string expr;                             // as written, e.g. "dpsi - dlambda2"
  std::vector<std::pair<std::string, double>> terms;  // (parameter name, coefficient)
  double value_si = 0.0;
  double sigma_si = 0.0;
};

// Where one of our channels comes from in the data file.
struct ColumnSource {
  std::string source;            // column or MAT variable name; empty when constant
  std::optional<double> constant;  // channel held at this value (file units)
  std::string unit;              // unit of the source: deg|rad (angles), mV|V|g|mg|m/s^2|counts (readings),
                                 // deg/s|rad/s|counts (gyro), s|ms
  std::optional<double> counts_per_g;  // readings in counts: the nominal count scale (required)
  std::optional<double> counts_per_dps;  // gyro in counts: counts per deg/s (required)
  double scale = 1.0;            // applied after the unit conversion
  double offset = 0.0;           // added after scaling, in our units (deg, mV, s)
};

// The gyro block of run.yaml (SPEC section 10): nominal scale (start value and
// prior mean), biases, and the reading noise per sample, SI inside:
//   gyro: {scale: [1, 1, 1], bias_dps: [0, 0, 0], noise_dps: 0.05 | [x, y, z] | auto}
struct GyroDescription {
  Eigen::Vector3d scale{1.0, 1.0, 1.0};
  Eigen::Vector3d bias_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d noise_rad_s = Eigen::Vector3d::Constant(0.05 * kDegToRad);
  bool noise_auto = false;  // estimated from the run (noise_rad_s is the start)
};

struct RunDescription {
  std::string yaml_path;   // the run.yaml itself (for messages)
  std::string data_path;   // resolved relative to run.yaml

  // bench
  Eigen::Vector3d lever_arm0_m{0.138, 0.020, 0.020};
  double angle_noise_rad = 15.0 * kArcsecToRad;
  double g_mps2 = kStandardGravity;
  // bench: {latitude_deg, heading_deg} (both or neither): Earth's rate is
  // added to the gyro's input rate (gyro_model.h).
  std::optional<double> latitude_rad, heading_rad;

  // triad (nominal values, start and prior mean)
  Eigen::Vector3d scale_mV_per_g{174.0, 174.0, 174.0};
  Eigen::Vector3d bias_mV{1500.0, 1500.0, 1500.0};
  // The reading noise, 1 sigma per sample [mV]: one figure for every
  // channel (noise_mV), or one per channel (noise_channel_mV, when given),
  // or `auto`: estimated from the run (noise_mV is then only the start).
  double noise_mV = 2.0;
  std::optional<Eigen::Vector3d> noise_channel_mV;
  bool noise_auto = false;
  Eigen::Vector3d ChannelNoise_mV() const {
    return noise_channel_mV ? *noise_channel_mV : Eigen::Vector3d::Constant(noise_mV);
  }

  // The gyro triad, when the run.yaml has a gyro block.
  std::optional<GyroDescription> gyro;

  std::vector<Constraint> constraints;

  // input mapping: keys are our channel names (t, lambda1, lambda2, wx, wy, wz,
  // lambda1_rate, lambda2_rate, temp_C, gx, gy, gz); absent keys use the CSV
  // contract names.
  std::map<std::string, ColumnSource> columns;
  // mounting: platform axis i carries IMU channel axis_source[i] times axis_sign[i].
  int axis_source[3] = {0, 1, 2};
  double axis_sign[3] = {1.0, 1.0, 1.0};

  // data_format (optional, text files beyond the CSV contract):
  //   header: [time, ax, ay, az]   the file has no header line; its columns, in order
  //   sort_by_time: true           rows stored out of time order (e.g. grouped by
  //                                label): sorted by t (stable) before the checks
  std::vector<std::string> data_header;
  bool sort_by_time = false;
  // positions (optional, used by `static` with columns.label): position label ->
  // the direction that points up, in the IMU's own axes (before mounting), as a
  // unit vector; "+x" is (1, 0, 0). Labels not listed (e.g. x_rot) are not
  // static positions. Empty: the Ferraris convention DefaultLabelPositions().
  std::map<std::string, Eigen::Vector3d> positions;

  // priors: {NAME: SIGMA} in file units: the 1 sigma of the weak prior on a
  // parameter around its nominal value; absent names use the defaults of
  // core/model/priors.h. (Parsed from the optional `priors:` key.)
  std::map<std::string, double> prior_sigma;

  // sensor (optional): which unit was calibrated, copied into the provenance
  // of every output: {serial: "SN 0042", model: "ADXL325"}; empty when absent.
  std::string sensor_serial;
  // time_range_s: [from, to]: only the samples with from <= t <= to [s].
  std::optional<std::pair<double, double>> time_range_s;
  // temperature_C: the run's temperature [degC], for a calibration with a
  // temperature model when the data have no temp_C column (docs/multi-run.md).
  std::optional<double> temperature_C;
  std::string sensor_model;
};

// The nominal parameter vector of this run (scale, bias from the triad section,
// everything else 0) in the given layout.
Eigen::VectorXd NominalTheta(const RunDescription& run, const ParameterLayout& layout);

// The triad's nominal scale and zero offset of each of the IMU's own axes
// (the readings columns, before the mounting): `triad` declares them per
// platform axis i, which carries IMU axis axis_source[i] times axis_sign[i].
struct ImuAxesNominal {
  double scale[3] = {1.0, 1.0, 1.0}, bias[3] = {0.0, 0.0, 0.0};
};
ImuAxesNominal NominalOfImuAxes(const RunDescription& run);

// The model configuration of this run (R0, g) for the given layout.
ModelConfig MakeModelConfig(const RunDescription& run, const ParameterLayout& layout);
// ... with the references its recorded data set: the first temp_C
// (thermal_drift_temp), the first sample time and the span (the quadratic drift).
ModelConfig MakeModelConfig(const RunDescription& run, const ParameterLayout& layout,
                            const RunData& data);

}  // namespace triadcal

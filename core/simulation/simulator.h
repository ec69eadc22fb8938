// The simulator: a scenario (docs/file-formats.md) -> a run (run.csv, run.yaml,
// truth.json). It uses the model of bench_model.h and nothing else for the
// physics, so data and estimators share one model.
//
// Scenario file (every section and key optional; defaults in the structs below):
//
//   profile: {amplitude_deg: [360, 90], period_s: [30, 12], phase_deg: [0, 0],
//             duration_s: 90, rate_hz: 100}
//   truth: {Kx: 171.5, dpsi: -33, dx2: -7}   # docs/file-formats.md names, file units;
//                                             # absent: nominal (Kx..Kz, W0x..W0z
//                                             # from run.triad) or 0; with a run.gyro
//                                             # block also gyro.Kx .. gyro.Gzz (nominal
//                                             # gyro.K*, gyro.W0* from run.gyro)
//   noise: {accel_mV: 2.0, angle_arcsec: 0}   # white, 1 sigma per sample; accel_mV
//                                             # may be [x, y, z], one per channel
//          # accel_correlation_s: 0.5 makes the reading noise first-order
//          # Gauss-Markov (correlated in time) with the same sigma per sample
//          # gyro_dps: 0.05 (or [x, y, z]), white, only with run.gyro
//   effects: {angle_latency: {tau_ms: 2}}     # injected into the data, NOT declared
//                                             # in run.yaml; a parameter is written
//                                             # as its name or name_unit (tau or
//                                             # tau_ms); absent parameters are 0
//   run: {bench: ..., triad: ..., constraints: ...}   # what run.yaml declares;
//        # bench.angle_noise_arcsec defaults to noise.angle_arcsec (0 included)
//        # and triad.noise_mV to the true reading noise sqrt(accel_mV^2 + q^2/12)
//        # (q = sensor.quantization_mV), at least kMinDeclaredNoise_mV since
//        # run.yaml needs noise_mV > 0; `data`, `columns` and `mounting` are not
//        # allowed (simulate writes the CSV contract itself)
//        # run.gyro: {scale, bias_dps, noise_dps} (SPEC section 10) makes the
//        # run carry a gyro triad: gx gy gz [deg/s] in run.csv; its noise_dps
//        # defaults to noise.gyro_dps (at least kMinDeclaredNoise_dps);
//        # run.bench.latitude_deg/heading_deg put Earth's rate into them
//   # optional keys beyond docs/file-formats.md:
//   seed: 1                                   # overridden by `simulate --seed N`
//   truth_spread: {dlambda2: 0.5}             # per-seed Gaussian spread added to
//                                             # the truth (file units), drawn from
//                                             # a stream of its own (SampleTruth):
//                                             # Monte Carlo over a population of
//                                             # sensors and benches
//   sensor: {quantization_mV: 0.5, saturation_mV: [0, 3300]}   # recording chain
//   temperature: {start_C: 25, rate_C_per_h: 10}   # temp_C(t) = start + rate t;
//                                             # required by thermal_drift_temp
//   truth_temperature: {reference_C: 20, per_C: {W0x: 0.05, Kx: 0.01}}
//                                             # truth is that of reference_C; the
//                                             # run's is truth + per_C (start_C -
//                                             # reference_C): runs of one IMU at
//                                             # several temperatures
//   output: {rates: false, temperature: <true when `temperature` is given>}
//                                             # write lambda1_rate/lambda2_rate
//                                             # (exact recorded rates) / temp_C
//
// Sample k (k = 0, 1, ... while t_k = double(k) / rate_hz < duration_s):
//
//   bench     = profile(t_k)                          (the bench moves with this)
//   recorded  = EncoderReading(profile(t_k - tau)) + angle noise
//   readings  = PredictReadings_mV(bench, t_k, temp_C(t_k)) + accel noise,
//               then rounded to multiples of quantization_mV, then clipped to
//               saturation_mV
//   gyro      = PredictGyroReadings(bench) + gyro noise   (with run.gyro; the
//               gyro_model.h readings at the true bench angles, rad/s inside,
//               deg/s in run.csv; no quantization or saturation)
//
// Noise: one std::mt19937_64 seeded with `seed` feeds one
// std::normal_distribution<double>(0, 1); per sample the draws are, in this
// order, lambda1, lambda2, wx, wy, wz, each times its sigma. All five are drawn
// even when a sigma is 0, so the sequence of one channel does not depend on the
// others. The gyro's noise (gx, gy, gz per sample) comes from a second
// std::mt19937_64 of its own (seeded from `seed`), so a gyro block leaves the
// accelerometer's data of a scenario unchanged. The same seed gives the same
// data with the same C++ standard library (the normal distribution's algorithm
// is implementation-defined).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/io/file_util.h"
#include "core/model/bench_model.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

// lambda_i(t) = A_i sin(2 pi t / T_i + phi_i)
struct HarmonicProfile {
  double amplitude_rad[2] = {360.0 * kDegToRad, 90.0 * kDegToRad};
  double period_s[2] = {30.0, 12.0};
  double phase_rad[2] = {0.0, 0.0};
  double duration_s = 90.0;
  double rate_hz = 100.0;

  BenchAngles<double> At(double t_s) const;  // exact angle, rate, acceleration
  // Number of samples t_k = double(k) / rate_hz < duration_s, and t_k itself.
  std::size_t NumSamples() const;
  double SampleTime_s(std::size_t k) const { return static_cast<double>(k) / rate_hz; }
};

struct Scenario {
  std::string yaml_path;
  HarmonicProfile profile;
  RunDescription run;            // what run.yaml declares
  ParameterLayout truth_layout;  // base + injected effects (+ the gyro block with run.gyro)
  Eigen::VectorXd truth;         // SI, in truth_layout
  // noise, 1 sigma per sample: one figure for every channel, or one per
  // channel (noise.accel_mV: [x, y, z]; accel_noise_mV is then their RMS)
  double accel_noise_mV = 2.0;
  std::optional<Eigen::Vector3d> accel_noise_channel_mV;
  Eigen::Vector3d AccelNoise_mV() const {
    return accel_noise_channel_mV ? *accel_noise_channel_mV
                                  : Eigen::Vector3d::Constant(accel_noise_mV);
  }
  // > 0: the reading noise is first-order Gauss-Markov with this correlation
  // time (same sigma per sample): residuals correlated in time
  double accel_correlation_s = 0.0;
  double angle_noise_rad = 0.0;
  // the gyro's reading noise per channel (noise.gyro_dps), used when run.gyro
  // is set; per_channel: given as [x, y, z]
  Eigen::Vector3d gyro_noise_rad_s = Eigen::Vector3d::Constant(0.05 * kDegToRad);
  bool gyro_noise_per_channel = false;
  // optional sensor imperfections of the recording chain
  double quantization_mV = 0.0;  // 0: none
  double saturation_low_mV = -1e300, saturation_high_mV = 1e300;
  // optional channels
  bool write_rates = false;
  double temp_start_C = 25.0, temp_rate_C_per_h = 0.0;
  bool write_temp = false;
  std::uint64_t seed = 1;
  // (parameter index, sigma SI): see truth_spread above
  std::vector<std::pair<int, double>> truth_spread;
};

// The truth of this seed: s.truth plus the truth_spread draws. Call after the
// seed is final; the data noise stream is not affected.
void SampleTruth(Scenario* s);

// The reading noise a run declares for noise-free data (run.yaml requires > 0).
constexpr double kMinDeclaredNoise_mV = 1e-3;
constexpr double kMinDeclaredNoise_dps = 1e-4;  // the gyro's

// Most samples a scenario may ask for (about 2 GB of run data).
constexpr std::size_t kMaxSimulatedSamples = 20000000;

// Reads and checks SCENARIO.yaml. Throws InputError "FILE: key.path: what is
// wrong" (or "FILE:LINE: ..." for YAML syntax errors).
Scenario LoadScenario(const std::string& yaml_path);

// Temperature of the scenario at time t [degC]: start_C + rate_C_per_h * t / 3600.
double ScenarioTemperature_C(const Scenario& s, double t_s);

// The model configuration the data are generated with: MakeModelConfig(run,
// truth_layout) with temp_ref_C = the temperature of the first sample.
ModelConfig TruthModelConfig(const Scenario& s);

// Generates the run: samples t_k = k / rate_hz < duration_s (with gx gy gz
// when s.run.gyro is set).
RunData Simulate(const Scenario& s);

// The key of parameter i of the layout in truth.json: base and gyro parameters
// by name ("Kx", "gyro.W0z"), effect parameters as effect.name_unit ("angle_latency.tau_ms", the
// the OUT form of docs/file-formats.md), and its value in file units, written with the fewest
// digits that read back (value * si_per_unit) to exactly theta[i].
std::string TruthFileKey(const ParameterLayout& layout, int i);
double TruthFileValue(const ParameterLayout& layout, const Eigen::VectorXd& theta, int i);

// Writes DIR/run.csv, DIR/run.yaml and DIR/truth.json (creating DIR). The
// three files are written under temporary names and renamed at the end, so a
// failure leaves none of them (and no DIR when this call created it).
//   run.csv     the CSV contract, with "# simulated by ...", "# scenario: NAME",
//               "# seed: N" comment lines
//   run.yaml    RunDescriptionToYaml(run, "run.csv"): injected effects NOT declared
//   truth.json  {"parameters": {"Kx": 171.5, ..., "angle_latency.tau_ms": 2},
//                "units": {...}, "injected_effects": [...], "scenario": NAME,
//                "seed": N, "noise": {"accel_mV", "angle_arcsec", "gyro_dps" (with a
//                gyro)}, "samples": N,
//                "provenance": {...}}  (provenance_json, when not empty)
// `options` go to every write (core/io/file_util.h).
void WriteSimulation(const Scenario& s, const RunData& data, const std::string& dir,
                     const std::string& provenance_json = "", const WriteOptions& options = {});

}  // namespace triadcal

// The harmonic bench profile and the generation of a simulated run (simulator.h):
// exact profile derivatives, the model of bench_model.h for the readings and
// the recorded angles, then noise, quantization and saturation; the gyro's
// readings from gyro_model.h.
#include "core/simulation/simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "core/model/errors.h"
#include "core/model/gyro_model.h"

namespace triadcal {

// lambda   = A sin(w t + phi),   w = 2 pi / T
// lambda'  = A w cos(w t + phi)
// lambda'' = -A w^2 sin(w t + phi)
BenchAngles<double> HarmonicProfile::At(double t_s) const {
  BenchAngles<double> b;
  for (int i = 0; i < 2; ++i) {
    const double w_rad_s = 2.0 * kPi / period_s[i];
    const double arg_rad = w_rad_s * t_s + phase_rad[i];
    const double s = std::sin(arg_rad), c = std::cos(arg_rad);
    b.axis[i].angle = amplitude_rad[i] * s;
    b.axis[i].rate = amplitude_rad[i] * w_rad_s * c;
    b.axis[i].accel = -amplitude_rad[i] * w_rad_s * w_rad_s * s;
  }
  return b;
}

std::size_t HarmonicProfile::NumSamples() const {
  if (!(duration_s > 0.0) || !(rate_hz > 0.0)) return 0;
  std::size_t n = static_cast<std::size_t>(std::ceil(duration_s * rate_hz));
  while (n > 0 && SampleTime_s(n - 1) >= duration_s) --n;
  while (SampleTime_s(n) < duration_s) ++n;
  return n;
}

double ScenarioTemperature_C(const Scenario& s, double t_s) {
  return s.temp_start_C + s.temp_rate_C_per_h * t_s / 3600.0;
}

ModelConfig TruthModelConfig(const Scenario& s) {
  ModelConfig cfg = MakeModelConfig(s.run, s.truth_layout);
  cfg.temp_ref_C = ScenarioTemperature_C(s, s.profile.SampleTime_s(0));
  // The span of the samples simulate writes.
  const std::size_t n = s.profile.NumSamples();
  cfg.time_start_s = s.profile.SampleTime_s(0);
  cfg.time_span_s = n > 0 ? s.profile.SampleTime_s(n - 1) - cfg.time_start_s : 0.0;
  return cfg;
}

RunData Simulate(const Scenario& s) {
  const ModelConfig cfg = TruthModelConfig(s);
  const double* theta = s.truth.data();
  const double tau_s = AngleLatency_s(cfg, theta);
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> unit_normal(0.0, 1.0);

  const std::size_t n = s.profile.NumSamples();
  RunData d;
  d.t_s.reserve(n);
  for (int i = 0; i < 2; ++i) {
    d.lambda_rad[i].reserve(n);
    if (s.write_rates) d.rate_rad_s[i].reserve(n);
  }
  for (int i = 0; i < 3; ++i) d.w_mV[i].reserve(n);
  if (s.write_temp) d.temp_C.reserve(n);
  const bool gyro = s.run.gyro.has_value();
  if (gyro && !cfg.layout.has_gyro()) {
    throw std::logic_error("Simulate: run.gyro without the gyro block in truth_layout");
  }
  if (gyro) {
    for (int i = 0; i < 3; ++i) d.gyro_rad_s[i].reserve(n);
  }
  // The gyro's noise: a stream of its own, so the accelerometer's draws are
  // those of the same scenario without a gyro.
  // (A distribution of its own too: std::normal_distribution keeps the second
  // value of each pair it draws.)
  std::mt19937_64 gyro_rng(s.seed ^ 0x6779726f6e6f6973ULL);
  std::normal_distribution<double> gyro_normal(0.0, 1.0);

  // Reading noise: white, or first-order Gauss-Markov with correlation time
  // accel_correlation_s (same per-sample sigma, the same unit draws).
  const double phi =
      s.accel_correlation_s > 0.0 ? std::exp(-1.0 / (s.profile.rate_hz * s.accel_correlation_s))
                                  : 0.0;
  double colour[3] = {0.0, 0.0, 0.0};
  const Eigen::Vector3d accel_sigma_mV = s.AccelNoise_mV();
  for (std::size_t k = 0; k < n; ++k) {
    const double t_s = s.profile.SampleTime_s(k);
    const SampleContext ctx{t_s, ScenarioTemperature_C(s, t_s)};
    // The bench moves with the profile; the angle sensors report it tau late.
    const BenchAngles<double> bench = s.profile.At(t_s);
    const BenchAngles<double> recorded = EncoderReading(cfg, theta, s.profile.At(t_s - tau_s));
    const Eigen::Vector3d readings_mV = PredictReadings_mV(cfg, theta, bench, ctx);

    // Draw order (documented in simulator.h): lambda1, lambda2, wx, wy, wz.
    double angle_noise[2], accel_noise[3];
    for (double& v : angle_noise) v = unit_normal(rng);
    for (int i = 0; i < 3; ++i) {
      const double w = unit_normal(rng);
      colour[i] = k == 0 ? w : phi * colour[i] + std::sqrt(1.0 - phi * phi) * w;
      accel_noise[i] = colour[i];
    }

    d.t_s.push_back(t_s);
    for (int i = 0; i < 2; ++i) {
      d.lambda_rad[i].push_back(recorded.axis[i].angle + s.angle_noise_rad * angle_noise[i]);
      if (s.write_rates) d.rate_rad_s[i].push_back(recorded.axis[i].rate);
    }
    // A scenario whose numbers overflow the model (a huge amplitude or truth
    // value) gives NaN or infinite readings, before any saturation: an error,
    // never a file of NaN (or of saturated nonsense).
    const double angle_sum = recorded.axis[0].angle + recorded.axis[1].angle;
    if (!std::isfinite(angle_sum) || !readings_mV.allFinite()) {
      char t_text[32];
      std::snprintf(t_text, sizeof(t_text), "%g", t_s);
      throw InputError(s.yaml_path + ": the simulated " +
                       (std::isfinite(angle_sum) ? "readings" : "angles") + " at t = " + t_text +
                       " s are not finite numbers: check the profile and truth values (a number "
                       "beyond what the model can evaluate)");
    }
    for (int i = 0; i < 3; ++i) {
      double w = readings_mV[i] + accel_sigma_mV[i] * accel_noise[i];
      if (s.quantization_mV > 0.0) w = std::round(w / s.quantization_mV) * s.quantization_mV;
      w = std::clamp(w, s.saturation_low_mV, s.saturation_high_mV);
      d.w_mV[i].push_back(w);
    }
    if (s.write_temp) d.temp_C.push_back(ctx.temp_C);
    if (gyro) {
      // At the bench's true angles (not the recorded ones), rad/s.
      const Eigen::Vector3d g_rad_s = PredictGyroReadings(cfg, theta, bench);
      if (!g_rad_s.allFinite()) {
        char t_text[32];
        std::snprintf(t_text, sizeof(t_text), "%g", t_s);
        throw InputError(s.yaml_path + ": the simulated gyro readings at t = " + t_text +
                         " s are not finite numbers: check the profile and the gyro.* truth "
                         "values");
      }
      for (int i = 0; i < 3; ++i) {
        d.gyro_rad_s[i].push_back(g_rad_s[i] + s.gyro_noise_rad_s[i] * gyro_normal(gyro_rng));
      }
    }
  }
  return d;
}

void SampleTruth(Scenario* s) {
  if (s->truth_spread.empty()) return;
  std::mt19937_64 rng(s->seed ^ 0x7275746873707264ULL);  // a stream apart from the noise
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const auto& [i, sigma] : s->truth_spread) s->truth[i] += sigma * normal(rng);
}

}  // namespace triadcal

// Block B1's cost per sample (the pass's inner loop, inertial_increments.cpp):
// the acceleration with its Jacobian by every parameter (AccelerationWithJacobian)
// and without it (AccelerationFromReadings_L), on the base layout with the
// nonlinearity at zero (the readings model linear: a run whose K_ij are held)
// and away from zero, with angle_latency (diagnose after its first round),
// with the size effect away from r = 0 (a refit of it in diagnose), and with
// every accelerometer candidate at zero (the pass of diagnose's score tests).
//   build/bench/triadcal_b1_speed [SAMPLES [CASE]]
//     (default 200000 samples a case; CASE 0-4: that case alone, for a profiler)
// Prints ns per sample, the median of 5 timings of one thread. Compare runs of
// one build against another on the same quiet machine, not across machines.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "core/model/b1_jacobian.h"
#include "core/model/bench_model.h"

namespace {

using namespace triadcal;

constexpr double kPi = 3.14159265358979323846;

struct Samples {
  std::vector<BenchAngles<double>> angles;
  std::vector<Eigen::Vector3d> readings_mV;
};

// The paper's profile's amplitudes (360 and 90 deg), rates and accelerations
// of its periods (30 and 12 s), readings about 1500 mV at 174 mV/g.
Samples Draw(std::size_t n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * kPi);
  std::normal_distribution<double> nrm(0.0, 1.0);
  Samples s;
  s.angles.resize(n);
  s.readings_mV.resize(n);
  const double amp[2] = {2.0 * kPi, 0.5 * kPi}, w[2] = {2.0 * kPi / 30.0, 2.0 * kPi / 12.0};
  for (std::size_t k = 0; k < n; ++k) {
    for (int i = 0; i < 2; ++i) {
      const double p = phase(rng);
      s.angles[k].axis[i] = {amp[i] * std::sin(p), amp[i] * w[i] * std::cos(p),
                             -amp[i] * w[i] * w[i] * std::sin(p)};
    }
    s.readings_mV[k] = Eigen::Vector3d(1500 + 174 * nrm(rng), 1500 + 174 * nrm(rng),
                                       1500 + 174 * nrm(rng));
  }
  return s;
}

template <typename F>
double NanosecondsPerSample(std::size_t n, F&& f) {
  std::vector<double> t;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t k = 0; k < n; ++k) f(k);
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return 1e9 * t[2] / static_cast<double>(n);
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 200000;
  if (n == 0) {
    std::fprintf(stderr, "triadcal_b1_speed: SAMPLES must be a positive integer\n");
    return 2;
  }
  const int only = argc > 2 ? std::atoi(argv[2]) : -1;
  if (argc > 2 && (std::string(argv[2]) != std::to_string(only) || only < 0 || only > 4)) {
    std::fprintf(stderr, "triadcal_b1_speed: CASE must be 0, 1, 2, 3 or 4\n");
    return 2;
  }
  const Samples s = Draw(n);
  std::printf("| layout | parameters | with Jacobian ns/sample | values only ns/sample |\n");
  std::printf("|---|---|---|---|\n");
  double sink = 0.0;
  for (int c = 0; c < 5; ++c) {
    if (only >= 0 && c != only) continue;
    ModelConfig cfg;
    cfg.temp_ref_C = 20.0;
    if (c == 2) cfg.layout = ParameterLayout({Effect::kAngleLatency});
    if (c == 3) cfg.layout = ParameterLayout({Effect::kAngleLatency, Effect::kSizeEffect});
    if (c == 4) {  // diagnose's score analysis of round 1: every candidate, at zero
      cfg.layout = ParameterLayout(
          {Effect::kAngleLatency, Effect::kEncoderHarmonic, Effect::kAxisNonintersection,
           Effect::kAxisNonperpendicularity, Effect::kSizeEffect, Effect::kThermalDrift,
           Effect::kScaleAsymmetry, Effect::kAngleScale, Effect::kCrossQuadratic,
           Effect::kThermalDriftQuadratic});
    }
    const int np = cfg.layout.size();
    Eigen::VectorXd th = Eigen::VectorXd::Zero(np);
    for (int i = 0; i < 3; ++i) th[kKx + i] = 174.0;
    for (int i = 0; i < 3; ++i) th[kW0x + i] = 1500.0;
    for (int i = kAlphaX; i <= kGammaZ; ++i) th[i] = 1e-3;
    if (c > 0) {
      for (int i = kKxx; i <= kKzz; ++i) th[i] = 1e-3;
    }
    if (c >= 2 && c < 4) th[cfg.layout.offset(Effect::kAngleLatency)] = -8.6e-3;
    if (c == 3) {  // the lever arm and the two sensing points a few mm off O
      th[kDx2] = 0.02;
      for (int q = 0; q < 6; ++q) th[cfg.layout.offset(Effect::kSizeEffect) + q] = 2e-3 * (q % 3 + 1);
    }
    Eigen::MatrixXd J(3, np);
    Eigen::Vector3d a;
    const double with = NanosecondsPerSample(n, [&](std::size_t k) {
      AccelerationWithJacobian(cfg, th.data(), s.angles[k], s.readings_mV[k],
                               SampleContext{0.01 * k, 20.0}, &a, J);
      sink += a[0] + J(1, kKx);
    });
    const double values = NanosecondsPerSample(n, [&](std::size_t k) {
      sink += AccelerationFromReadings_L<double>(cfg, th.data(), s.angles[k], s.readings_mV[k],
                                                 SampleContext{0.01 * k, 20.0})[0];
    });
    const char* name[5] = {"base, K_ij = 0", "base, K_ij = 1e-3 /g", "base + angle_latency",
                           "base + angle_latency + size_effect (r != 0)",
                           "base + every accelerometer candidate at zero (a score analysis)"};
    std::printf("| %s | %d | %.0f | %.0f |\n", name[c], np, with, values);
  }
  if (sink == 0.123456789) std::printf("\n");  // keeps the work
  return 0;
}

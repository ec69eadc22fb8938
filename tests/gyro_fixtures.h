// A simulated paper run with a gyro triad (SPEC section 10) for the
// estimators' tests: the gyro block's truth and its readings made from the
// exact bench angles (gyro_term_test, gyro_measurements_test).
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "core/model/gyro_model.h"
#include "core/model/run_description.h"
#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace testing_fixtures {

// A truth for the gyro block (file units) and the run's gyro readings made
// from the exact bench angles, with white noise of noise_dps per channel.
struct GyroRun {
  Scenario s;
  ParameterLayout layout;
  Eigen::VectorXd truth;  // SI, in layout
  RunData data;
};

// shape (optional) edits the scenario (its profile) before it is simulated.
inline GyroRun MakeGyroRun(double rate_hz, double duration_s, double noise_dps, std::uint64_t seed,
                           const std::vector<Effect>& effects = {},
                           const NamedValues& effect_truth = {},
                           const std::function<void(Scenario*)>& shape = nullptr) {
  GyroRun g;
  g.s = PaperScenario(rate_hz, duration_s, 2.0, 15.0, seed);
  if (shape) shape(&g.s);
  if (!effects.empty()) {
    // Effects in the data (the accelerometer's through the simulator, the
    // gyro's input rate is the bench's own).
    g.s.truth_layout = ParameterLayout(effects);
    Eigen::VectorXd t = Eigen::VectorXd::Zero(g.s.truth_layout.size());
    t.head(kNumBaseParams) = g.s.truth;
    g.s.truth = t;
    SetFromFileUnits(g.s.truth_layout, effect_truth, &g.s.truth);
  }
  std::mt19937_64 rng(seed * 7919 + 17);
  std::normal_distribution<double> n01;
  // The pseudo-measurement dpsi - dlambda2 = 0 +- 30'' is a measurement: its
  // error drawn, as on a real bench (with the truth on it exactly, the sigma
  // of dlambda2 and of what leans on it, the gyro's gamma_y and gamma_z, is
  // an over-statement: RMS z 0.82 over 200 seeds).
  g.s.truth[kDlambda2] = g.s.truth[kDpsi] + 30.0 * kArcsecToRad * n01(rng);
  g.data = Simulate(g.s);
  g.layout = ParameterLayout(effects, true);
  g.truth = Eigen::VectorXd::Zero(g.layout.size());
  g.truth.head(g.s.truth.size()) = g.s.truth;
  const int go = g.layout.gyro_offset();
  for (int i = 0; i < 3; ++i) g.truth[go + kGKx + i] = 1.0;
  SetFromFileUnits(g.layout,
                   {{"gyro.Kx", 1.004}, {"gyro.Ky", 0.997}, {"gyro.Kz", 1.002},
                    {"gyro.W0x", 0.31}, {"gyro.W0y", -0.52}, {"gyro.W0z", 0.12},
                    {"gyro.alpha_x", 12}, {"gyro.alpha_y", -20}, {"gyro.beta_x", 8},
                    {"gyro.beta_z", 15}, {"gyro.gamma_y", -9}, {"gyro.gamma_z", 25},
                    {"gyro.Gxx", 0.05}, {"gyro.Gyz", -0.08}, {"gyro.Gzy", 0.03}},
                   &g.truth);
  ModelConfig cfg = MakeModelConfig(g.s.run, g.layout, g.data);
  for (int i = 0; i < 3; ++i) g.data.gyro_rad_s[i].resize(g.data.size());
  for (std::size_t k = 0; k < g.data.size(); ++k) {
    const BenchAngles<double> b = g.s.profile.At(g.data.t_s[k]);
    const Eigen::Vector3d G = PredictGyroReadings<double>(cfg, g.truth.data(), b);
    for (int i = 0; i < 3; ++i) g.data.gyro_rad_s[i][k] = G[i] + noise_dps * kDegToRad * n01(rng);
  }
  GyroDescription gd;
  gd.noise_rad_s = Eigen::Vector3d::Constant(noise_dps * kDegToRad);
  g.s.run.gyro = gd;
  return g;
}

}  // namespace testing_fixtures
}  // namespace triadcal

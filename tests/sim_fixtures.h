// Simulated runs for estimator tests: the paper's experiment 3 (Table 2 truth)
// built in code, so that tests do not depend on example files.
#pragma once

#include <cstdint>

#include "core/simulation/simulator.h"
#include "core/model/units.h"

namespace triadcal {
namespace testing_fixtures {

inline Scenario PaperScenario(double rate_hz, double duration_s, double noise_mV,
                              double angle_noise_arcsec, std::uint64_t seed) {
  Scenario s;
  s.profile.rate_hz = rate_hz;
  s.profile.duration_s = duration_s;
  s.accel_noise_mV = noise_mV;
  s.angle_noise_rad = angle_noise_arcsec * kArcsecToRad;
  s.seed = seed;
  s.run.noise_mV = noise_mV;
  s.run.angle_noise_rad = s.angle_noise_rad;
  Constraint c;
  c.expr = "dpsi - dlambda2";
  c.terms = {{"dpsi", 1.0}, {"dlambda2", -1.0}};
  c.value_si = 0.0;
  c.sigma_si = 30.0 * kArcsecToRad;
  s.run.constraints = {c};
  s.truth_layout = ParameterLayout();
  s.truth = NominalTheta(s.run, s.truth_layout);
  SetFromFileUnits(s.truth_layout,
                   {{"Kx", 171.5}, {"Ky", 175.8}, {"Kz", 174.8}, {"W0x", 1504.2},
                    {"W0y", 1504.2}, {"W0z", 1504.3}, {"alpha_y", -32}, {"beta_z", 26},
                    {"alpha_x", 16}, {"gamma_z", 64}, {"beta_x", 11}, {"gamma_y", 140},
                    {"Kxx", 2e-3}, {"Kyz", -1e-3}, {"Kzy", 1.5e-3},
                    {"dpsi", -33}, {"dtheta_c", 43}, {"dlambda2", -33},
                    {"dx2", -7}, {"dy2", 16}, {"dz2", 4}},
                   &s.truth);
  return s;
}

// The paper run (50 Hz, 90 s, 2 mV, 15") with one catalogue effect in its
// truth, undeclared in run.yaml.
inline Scenario WithEffect(std::uint64_t seed, Effect e, const NamedValues& values) {
  Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, seed);
  s.truth_layout = ParameterLayout({e});
  Eigen::VectorXd t = Eigen::VectorXd::Zero(s.truth_layout.size());
  t.head(kNumBaseParams) = s.truth;
  s.truth = t;
  SetFromFileUnits(s.truth_layout, values, &s.truth);
  return s;
}

}  // namespace testing_fixtures
}  // namespace triadcal

// The reading noise estimated with the parameters (run_evaluation.h): sigma
// must rest on the noise the run has, whatever run.yaml declares.
#include "solvers/estimation/noise_estimation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <gtest/gtest.h>

#include "core/model/errors.h"
#include "solvers/estimation/batch_solver.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

// The paper's profile, 50 Hz, 60 s, 2 mV true noise. With the noise declared
// right and not re-estimated, sigma is the Cramer-Rao bound of the true noise.
// Declared 10x too small or 3x too large: the estimate finds 2 mV and sigma
// comes back to the bound (0.85-1.2 of it for every parameter).
TEST(NoiseEstimation, SigmaRestsOnTheNoiseTheRunHas) {
  Scenario s = PaperScenario(50.0, 60.0, 2.0, 15.0, 3);
  const RunData data = Simulate(s);
  const ParameterLayout layout;
  BatchOptions ref_opt;
  ref_opt.estimate_noise = false;
  const BatchResult ref = SolveBatch(s.run, data, layout, ref_opt);
  EXPECT_TRUE(ref.noise_check.consistent);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(ref.noise_check.estimated_mV[c], 2.0, 3.0 * ref.noise_check.sd_mV[c]) << c;
    // 120 intervals x 6 components share the 3 channels: ~240 each.
    EXPECT_GT(ref.noise_check.dof[c], 200.0) << c;
  }
  for (const double declared : {0.2, 6.0}) {
    SCOPED_TRACE(declared);
    Scenario d = s;
    d.run.noise_mV = declared;
    const BatchResult r = SolveBatch(d.run, data, layout, BatchOptions());
    ASSERT_TRUE(r.converged);
    EXPECT_FALSE(r.noise_check.consistent);
    EXPECT_EQ(r.noise_source, "estimated");
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(r.noise_used_mV[c], 2.0, 3.0 * r.noise_check.sd_mV[c]) << c;
      EXPECT_NEAR(r.noise_declared_mV[c], declared, 1e-12) << c;
    }
    for (int i = 0; i < kNumBaseParams; ++i) {
      if (ref.estimate.cov(i, i) <= 0.0) continue;  // held
      const double ratio = std::sqrt(r.estimate.cov(i, i) / ref.estimate.cov(i, i));
      EXPECT_GT(ratio, 0.85) << layout.info(i).name;
      EXPECT_LT(ratio, 1.2) << layout.info(i).name;
    }
  }
}

// An undeclared 20-ms angle latency on the paper's profile: the misfit
// falls unequally on the channels, and each channel's noise is estimated
// with it (the likelihood's own maximum, no rule about whiteness); the
// residual is far from white, so sigma is the HAC sandwich, never below the
// model's.
TEST(NoiseEstimation, MisfitIsCarriedByTheNoiseAndTheSandwich) {
  Scenario s = testing_fixtures::WithEffect(2, Effect::kAngleLatency, {{"angle_latency.tau", 20.0}});
  const RunData data = Simulate(s);
  const BatchResult r = SolveBatch(s.run, data, ParameterLayout(), BatchOptions());
  ASSERT_TRUE(r.converged) << r.termination;
  EXPECT_EQ(r.noise_source, "estimated");
  EXPECT_FALSE(r.noise_check.consistent);
  EXPECT_GT(r.noise_used_mV.maxCoeff(), 2.2);  // the misfit counts
  EXPECT_NEAR(r.chi2_per_dof, 1.0, 0.05);
  EXPECT_FALSE(r.residual_white);
  EXPECT_EQ(r.sigma_method, "hac");
  for (int i = 0; i < kNumBaseParams; ++i) {
    if (r.cov_white(i, i) <= 0.0) continue;
    EXPECT_GE(r.estimate.cov(i, i), r.cov_white(i, i) * (1 - 1e-12))
        << ParameterLayout().info(i).name;
  }
}

// Channels alike and residual white: each channel's estimate is its noise.
TEST(NoiseEstimation, CleanRunIsEstimatedPerChannel) {
  Scenario s = PaperScenario(50.0, 60.0, 2.0, 15.0, 4);
  s.run.noise_mV = 0.5;
  const RunData data = Simulate(s);
  const BatchResult r = SolveBatch(s.run, data, ParameterLayout(), BatchOptions());
  EXPECT_TRUE(r.noise_check.white);
  EXPECT_EQ(r.noise_source, "estimated");
  EXPECT_LT(r.noise_check.lag1.cwiseAbs().maxCoeff(), 0.2);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.noise_used_mV[c], 2.0, 4.0 * r.noise_check.sd_mV[c]);
}

// White reading noise of 2 / 10 / 2 mV, not declared: each channel gets its
// own noise, so the fit is the one weighted with the true noise: every sigma
// within 10 % of that fit's (the Cramer-Rao bound of the per-channel noise)
// and the estimates within a small fraction of sigma of it.
TEST(NoiseEstimation, ChannelsThatDifferAreWeightedByTheirOwnNoise) {
  Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, 8);
  s.accel_noise_channel_mV = Eigen::Vector3d(2.0, 10.0, 2.0);
  s.run.noise_auto = true;
  const RunData data = Simulate(s);
  const ParameterLayout layout;
  const BatchResult r = SolveBatch(s.run, data, layout, BatchOptions());
  ASSERT_TRUE(r.converged) << r.termination;
  EXPECT_TRUE(r.residual_white);
  EXPECT_EQ(r.sigma_method, "white");
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(r.noise_used_mV[c], (*s.accel_noise_channel_mV)[c], 4.0 * r.noise_check.sd_mV[c]);
  }
  RunDescription truly = s.run;
  truly.noise_auto = false;
  truly.noise_channel_mV = Eigen::Vector3d(2.0, 10.0, 2.0);
  BatchOptions declared;
  declared.estimate_noise = false;
  const BatchResult ref = SolveBatch(truly, data, layout, declared);
  for (int i = 0; i < kNumBaseParams; ++i) {
    if (ref.estimate.cov(i, i) <= 0.0 || r.estimate.cov(i, i) <= 0.0) continue;
    const double bound = std::sqrt(ref.estimate.cov(i, i));
    EXPECT_NEAR(std::sqrt(r.estimate.cov(i, i)) / bound, 1.0, 0.1) << layout.info(i).name;
    EXPECT_NEAR(r.estimate.theta[i], ref.estimate.theta[i], 0.2 * bound) << layout.info(i).name;
  }
}

TEST(NoiseEstimation, AutoFindsTheNoise) {
  Scenario s = PaperScenario(50.0, 60.0, 3.0, 15.0, 5);
  s.run.noise_auto = true;
  s.run.noise_mV = 1.0;  // only the start
  const RunData data = Simulate(s);
  const BatchResult r = SolveBatch(s.run, data, ParameterLayout(), BatchOptions());
  EXPECT_EQ(r.noise_source, "estimated");
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(r.noise_used_mV[c], 3.0, 3.0 * r.noise_check.sd_mV[c] + 0.03) << c;
  }
}

TEST(NoiseEstimation, AutoOnARunTooShortIsAnError) {
  Scenario s = PaperScenario(10.0, 3.0, 2.0, 15.0, 1);
  s.run.noise_auto = true;
  s.run.yaml_path = "short.yaml";
  const RunData data = Simulate(s);
  try {
    SolveBatch(s.run, data, ParameterLayout(), BatchOptions());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("short.yaml: triad.noise_mV: auto needs a longer run"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace triadcal

// Closing the loop for the gyro (issue 33): simulated paper runs with a gyro
// (tests/gyro_fixtures.h; 50 Hz, 90 s, gyro noise 0.05 deg/s) carrying one
// gyro-stage effect that the run does not declare. `diagnose`, over the whole
// catalogue, selects it through the gyro's part of its score test and
// likelihood ratio; the gyro's negative log-likelihood falls and the
// effect's estimate ends within 4 sigma of the truth. A clean gyro run
// selects neither.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "solvers/diagnosis/effect_discovery.h"
#include "tests/gyro_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::GyroRun;
using testing_fixtures::MakeGyroRun;

bool Selected(const DiagnosisResult& d, Effect e) {
  return std::find(d.selected.begin(), d.selected.end(), e) != d.selected.end();
}

std::string Names(const std::vector<Effect>& v) {
  std::string s;
  for (Effect e : v) s += (s.empty() ? "" : ", ") + GetEffectSpec(e).name;
  return s.empty() ? "none" : s;
}

void ExpectFound(Effect effect, const NamedValues& truth, std::uint64_t seed) {
  const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, seed, {effect}, truth);
  const DiagnosisResult d = Diagnose(g.s.run, g.data, {});
  const EffectSpec& spec = GetEffectSpec(effect);
  std::printf("%s seed %d: selected %s; gyro nll %.1f -> %.1f, noise %.4f -> %.4f deg/s\n",
              spec.name.c_str(), static_cast<int>(seed), Names(d.selected).c_str(),
              d.before.gyro.neg_log_likelihood, d.after.gyro.neg_log_likelihood,
              d.before.gyro.noise_rad_s.maxCoeff() / kDegToRad,
              d.after.gyro.noise_rad_s.maxCoeff() / kDegToRad);
  for (const CandidateTest& t : d.ranking) {
    if (GetEffectSpec(t.effect).stage != EffectStage::kGyro) continue;
    std::printf("  ranked %-22s score %.1f lr %.1f p %.3g\n", GetEffectSpec(t.effect).name.c_str(),
                t.score, t.lr, t.p_value);
  }
  ASSERT_TRUE(Selected(d, effect)) << d.verdict;
  EXPECT_LT(d.after.gyro.neg_log_likelihood, d.before.gyro.neg_log_likelihood);
  EXPECT_LT(d.after.gyro.noise_rad_s.maxCoeff(), d.before.gyro.noise_rad_s.maxCoeff());
  const ParameterLayout& L = d.after_layout;
  for (std::size_t q = 0; q < spec.params.size(); ++q) {
    const int i = L.offset(effect) + static_cast<int>(q);
    const std::string& name = L.info(i).name;
    const double truth_si = g.truth[g.layout.IndexOf(name)];
    const double sigma = std::sqrt(d.after.estimate.cov(i, i));
    const double f = L.info(i).si_per_unit;
    std::printf("  %-26s %9.4g +- %.3g (truth %.4g) %s\n", name.c_str(),
                d.after.estimate.theta[i] / f, sigma / f, truth_si / f, L.info(i).unit.c_str());
    EXPECT_LT(std::abs(d.after.estimate.theta[i] - truth_si) / sigma, 4.0) << name;
  }
}

TEST(GyroEffectDiscovery, FindsAnUndeclaredGyroScaleAsymmetry) {
  ExpectFound(Effect::kGyroScaleAsymmetry,
              {{"gyro_scale_asymmetry.dKx", 3000.0},
               {"gyro_scale_asymmetry.dKy", -2000.0},
               {"gyro_scale_asymmetry.dKz", 1000.0}},
              51);
}

TEST(GyroEffectDiscovery, FindsAnUndeclaredGyroNonlinearity) {
  ExpectFound(Effect::kGyroNonlinearity,
              {{"gyro_nonlinearity.k2_x", 0.05},
               {"gyro_nonlinearity.k2_y", -0.2},
               {"gyro_nonlinearity.k2_z", 0.15}},
              52);
}

TEST(GyroEffectDiscovery, CleanGyroRunSelectsNeither) {
  for (std::uint64_t seed : {53, 54}) {
    const GyroRun g = MakeGyroRun(50.0, 90.0, 0.05, seed);
    const DiagnosisResult d = Diagnose(g.s.run, g.data, {});
    std::printf("clean seed %d: selected %s\n", static_cast<int>(seed), Names(d.selected).c_str());
    for (const CandidateTest& t : d.ranking) {
      if (GetEffectSpec(t.effect).stage != EffectStage::kGyro) continue;
      std::printf("  ranked %-22s score %.1f lr %.1f p %.3g\n",
                  GetEffectSpec(t.effect).name.c_str(), t.score, t.lr, t.p_value);
    }
    EXPECT_FALSE(Selected(d, Effect::kGyroScaleAsymmetry)) << d.verdict;
    EXPECT_FALSE(Selected(d, Effect::kGyroNonlinearity)) << d.verdict;
  }
}

}  // namespace
}  // namespace triadcal

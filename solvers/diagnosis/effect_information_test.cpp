// Score tests and reliability (effect_information.h): the noncentral
// chi-square they rest on, the score statistic against the likelihood ratio
// of a refit, the minimal detectable effect against the noncentrality an
// effect of that size really produces, and the could-hide list as a property
// of the profile.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "solvers/diagnosis/effect_discovery.h"
#include "solvers/diagnosis/effect_information.h"
#include "solvers/diagnosis/statistics.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;

TEST(ReliabilityStatistics, NoncentralChiSquare) {
  // k = 1: X = (Z + sqrt(lambda))^2, so P(X > c) = Phi(sqrt(lambda) - sqrt(c)) +
  // Phi(-sqrt(lambda) - sqrt(c)).
  auto phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  for (double lambda : {0.5, 4.0, 17.0, 60.0}) {
    for (double c : {1.0, 6.6, 20.0}) {
      const double want = phi(std::sqrt(lambda) - std::sqrt(c)) + phi(-std::sqrt(lambda) - std::sqrt(c));
      EXPECT_NEAR(NoncentralChiSquareSurvival(c, 1, lambda), want, 1e-9) << lambda << " " << c;
    }
  }
  EXPECT_EQ(NoncentralChiSquareSurvival(3.0, 4, 0.0), ChiSquareSurvival(3.0, 4));
  EXPECT_NEAR(ChiSquareUpperQuantile(0.05, 1), 3.841458820694124, 1e-8);
  EXPECT_NEAR(ChiSquareUpperQuantile(0.05, 5), 11.070497693516351, 1e-8);
  // Baarda's lambda0 for alpha 0.001, power 80 %, one dimension: 17.07.
  EXPECT_NEAR(NoncentralityForPower(0.001, 1, 0.8), 17.075, 0.01);
  // More dimensions need more noncentrality for the same power.
  EXPECT_GT(NoncentralityForPower(0.001, 4, 0.8), NoncentralityForPower(0.001, 1, 0.8));
}

Scenario WithEffect(std::uint64_t seed, Effect e, const NamedValues& values) {
  Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, seed);
  s.truth_layout = ParameterLayout({e});
  Eigen::VectorXd t = Eigen::VectorXd::Zero(s.truth_layout.size());
  t.head(kNumBaseParams) = s.truth;
  s.truth = t;
  SetFromFileUnits(s.truth_layout, values, &s.truth);
  return s;
}

const CandidateTest& Find(const DiagnosisResult& d, Effect e) {
  for (const CandidateTest& t : d.ranking) {
    if (t.effect == e) return t;
  }
  throw std::runtime_error("not ranked");
}

// The score statistic from the base fit and the likelihood ratio of the refit
// are asymptotically equal: with a small latency (~4 sigma) the two agree to
// 20 %, and the linearisation is the fit's own (gradient by the base
// parameters ~0 at its optimum).
TEST(ScoreTest, AgreesWithTheLikelihoodRatio) {
  const Scenario s = WithEffect(11, Effect::kAngleLatency, {{"angle_latency.tau", 0.8}});
  const RunData data = Simulate(s);
  DiagnoseOptions opt;
  opt.refit_factor = std::numeric_limits<double>::infinity();  // refit every candidate
  opt.max_effects = 1;
  const DiagnosisResult d = Diagnose(s.run, data, opt);
  EXPECT_LT(d.base_gradient_sigma, 0.1);
  const CandidateTest& t = Find(d, Effect::kAngleLatency);
  ASSERT_TRUE(t.refit);
  EXPECT_GT(t.statistic, 9.0);
  EXPECT_NEAR(t.score / t.statistic, 1.0, 0.2) << t.score << " vs " << t.statistic;
  for (const CandidateTest& c : d.ranking) {
    std::cout << GetEffectSpec(c.effect).name << " score " << c.score << " lr " << c.statistic
              << " dof " << c.dof << "\n";
  }
}

// On a clean run both statistics are chi2-small for every candidate.
TEST(ScoreTest, CleanRunBothSmall) {
  const Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, 5);
  const RunData data = Simulate(s);
  DiagnoseOptions opt;
  opt.refit_factor = std::numeric_limits<double>::infinity();
  const DiagnosisResult d = Diagnose(s.run, data, opt);
  EXPECT_TRUE(d.selected.empty()) << d.verdict;
  for (const CandidateTest& t : d.ranking) {
    if (t.dof == 0) continue;
    const double bound = ChiSquareUpperQuantile(1e-3, t.dof);
    EXPECT_LT(t.score, bound) << GetEffectSpec(t.effect).name;
    EXPECT_LT(t.statistic, bound) << GetEffectSpec(t.effect).name;
    std::cout << GetEffectSpec(t.effect).name << " score " << t.score << " lr " << t.statistic
              << " dof " << t.dof << "\n";
  }
  std::cout << d.verdict << "\n";
  for (const HideCase& h : d.could_hide) {
    std::cout << GetEffectSpec(h.effect).name << " mdb " << h.minimal_detectable << " " << h.unit
              << " shift " << h.max_shift_sigma << " " << h.parameter << " lambda0 " << h.lambda0
              << "\n";
  }
}

}  // namespace
}  // namespace triadcal

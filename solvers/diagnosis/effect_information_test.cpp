// Score tests and reliability (effect_information.h): the noncentral
// chi-square they rest on, the score statistic against the likelihood ratio
// of a refit, the minimal detectable effect against the noncentrality an
// effect of that size really produces, and the could-hide list as a property
// of the profile.
#include "solvers/diagnosis/effect_information.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "solvers/diagnosis/effect_discovery.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/statistics/statistics.h"
#include "tests/sim_fixtures.h"

namespace triadcal {
namespace {

using testing_fixtures::PaperScenario;
using testing_fixtures::WithEffect;

TEST(ReliabilityStatistics, NoncentralChiSquare) {
  // k = 1: X = (Z + sqrt(lambda))^2, so P(X > c) = Phi(sqrt(lambda) - sqrt(c)) +
  // Phi(-sqrt(lambda) - sqrt(c)).
  auto phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  for (double lambda : {0.5, 4.0, 17.0, 60.0}) {
    for (double c : {1.0, 6.6, 20.0}) {
      const double want =
          phi(std::sqrt(lambda) - std::sqrt(c)) + phi(-std::sqrt(lambda) - std::sqrt(c));
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
  }
  // The verdict does not call the run clean without what could hide.
  EXPECT_NE(d.verdict.find("could hide"), std::string::npos) << d.verdict;
  EXPECT_FALSE(d.could_hide.empty());
}

const HideCase& FindHide(const DiagnosisResult& d, Effect e) {
  for (const HideCase& h : d.could_hide) {
    if (h.effect == e) return h;
  }
  throw std::runtime_error("not in could_hide");
}

DiagnosisResult CouldHide(const Scenario& s) {
  DiagnoseOptions opt;
  opt.max_effects = 0;  // the declared model's reliability, no selection
  opt.fit.estimate_noise = false;  // the declared noise: the yardstick of the noise-free runs
  return Diagnose(s.run, Simulate(s), opt);
}

// The minimal detectable effect is what its name says: noise-free data with
// the effect at that size (along the stated direction) give a test statistic
// equal to the noncentrality lambda0 of 80 % power (noise-free, the statistic
// IS the noncentrality), and the declared model's fit of them moves the named
// parameter by the stated number of sigma (for a one-parameter effect the
// largest shift is reached at the MDB itself; with more, the stated largest
// shift bounds every parameter's). Measured: LR 16.24 for lambda0 16.24
// (latency), 20.64 for 20.62 (drift), shift 1.002 x the stated one.
TEST(Reliability, MinimalDetectableEffectGivesItsNoncentrality) {
  const DiagnosisResult clean = CouldHide(PaperScenario(50.0, 90.0, 2.0, 15.0, 21));
  for (Effect e : {Effect::kAngleLatency, Effect::kThermalDrift}) {
    const HideCase& h = FindHide(clean, e);
    ASSERT_FALSE(h.direction.empty()) << GetEffectSpec(e).name;
    NamedValues values;
    for (const auto& [name, v] : h.direction) values[GetEffectSpec(e).name + "." + name] = v;
    Scenario s = WithEffect(21, e, values);
    s.accel_noise_mV = 0.0;
    s.angle_noise_rad = 0.0;
    DiagnoseOptions opt;
    opt.candidates = {e};
    opt.refit_factor = std::numeric_limits<double>::infinity();
    opt.max_effects = 1;
    opt.fit.estimate_noise = false;  // noise-free: the declared noise is the yardstick
    const DiagnosisResult d = Diagnose(s.run, Simulate(s), opt);
    const CandidateTest& t = Find(d, e);
    ASSERT_TRUE(t.refit);
    EXPECT_NEAR(t.lr / h.lambda0, 1.0, 0.1)
        << GetEffectSpec(e).name << " " << t.lr << " vs " << h.lambda0;
    EXPECT_NEAR(t.score / h.lambda0, 1.0, 0.1) << GetEffectSpec(e).name;
    // External reliability: the declared model's shifts, in its sigma.
    double worst = 0.0;
    std::string worst_name;
    for (int i = 0; i < d.before_layout.size(); ++i) {
      const std::string& name = d.before_layout.info(i).name;
      const double sigma = std::sqrt(d.before.estimate.cov(i, i));
      if (sigma <= 0.0) continue;
      const double shift = std::abs(d.before.estimate.theta[i] - s.truth[i]) / sigma;
      if (shift > worst) {
        worst = shift;
        worst_name = name;
      }
    }
    EXPECT_LT(worst, 1.1 * h.max_shift_sigma) << GetEffectSpec(e).name << " " << worst_name;
    if (h.direction.size() == 1) {
      EXPECT_EQ(worst_name, h.parameter);
      EXPECT_NEAR(worst / h.max_shift_sigma, 1.0, 0.1) << GetEffectSpec(e).name;
    }
  }
}

// A considered parameter (batch_solver.h) stays at its nominal value in a
// refit, its prior uncertainty carried into the effect's sigma; the
// information a minimal detectable effect is found from (N) carries it too,
// so that the MDE is the size the refit's Wald test detects. angle_latency
// (its prior is nothing beside the data's information) against dz2 and
// dtheta_c made considered: N^-1 is the refit's variance to 2e-4, of which
// the consider term is 68 % and 95 % (N given them at nominal was 3 and 18
// times too large).
TEST(Reliability, CandidateInformationCarriesTheConsideredParameters) {
  const Scenario s = PaperScenario(50.0, 90.0, 2.0, 15.0, 21);
  const RunData data = Simulate(s);
  const HoldDecision decision =
      ChooseHeldParameters(s.run, data, ParameterLayout(), {}, 0.5, {});
  ASSERT_TRUE(decision.consider.empty());
  for (const char* considered : {"dz2", "dtheta_c"}) {
    HoldDecision with = decision;
    with.consider = {considered};  // as if the run did not determine it
    BatchOptions o;
    o.decision = &with;
    o.estimate_noise = false;
    o.sigma = "white";
    const BatchResult fit = SolveBatch(s.run, data, ParameterLayout(), o);
    const Effect e = Effect::kAngleLatency;
    const EffectInformation info = AnalyseCandidates(s.run, data, {}, fit, {e}, o);
    const CandidateInformation& c = info.candidates[0];
    ASSERT_EQ(c.supported.size(), 1u);
    const ParameterLayout aug({e});
    const BatchResult refit = SolveBatch(s.run, data, aug, o);
    const int i = aug.offset(e);
    const double var = refit.estimate.cov(i, i);
    ASSERT_LT(refit.cov_given_consider(i, i), 0.5 * var) << considered;  // the term matters
    EXPECT_NEAR(1.0 / (c.N(0, 0) * var), 1.0, 1e-3) << considered;
  }
}

// What could hide is a property of the profile, not of the noise: two seeds
// name the same effects moving parameters by more than 1 sigma, with the same
// minimal detectable sizes.
TEST(Reliability, CouldHideIsAPropertyOfTheProfile) {
  const DiagnosisResult a = CouldHide(PaperScenario(50.0, 90.0, 2.0, 15.0, 31));
  const DiagnosisResult b = CouldHide(PaperScenario(50.0, 90.0, 2.0, 15.0, 32));
  ASSERT_EQ(a.could_hide.size(), b.could_hide.size());
  for (const HideCase& h : a.could_hide) {
    const HideCase& g = FindHide(b, h.effect);
    EXPECT_EQ(h.max_shift_sigma > 1.0, g.max_shift_sigma > 1.0) << GetEffectSpec(h.effect).name;
    EXPECT_EQ(h.direction.size(), g.direction.size()) << GetEffectSpec(h.effect).name;
    if (!h.direction.empty()) {
      EXPECT_NEAR(g.minimal_detectable / h.minimal_detectable, 1.0, 0.15)
          << GetEffectSpec(h.effect).name;
    }
  }
}

}  // namespace
}  // namespace triadcal

namespace triadcal {
namespace {

// The score of the well-determined components alone (statistic_strong) is
// the score of a nested model: never above the full one, equal to it when no
// component is weak. On a single-axis run cross_quadratic has both kinds
// (its x_yy_zz and z_xx_yy are nearly W0 + K_ii there).
TEST(ScoreTest, WellDeterminedComponentsAloneScoreNoMoreThanAll) {
  Scenario s = testing_fixtures::PaperScenario(50.0, 90.0, 2.0, 15.0, 3);
  s.profile.amplitude_rad[1] = 0.0;
  const RunData data = Simulate(s);
  BatchOptions o = DiagnoseOptions().fit;
  o.estimate_noise = false;
  const BatchResult fit = SolveBatch(s.run, data, ParameterLayout(), o);
  const EffectInformation info = AnalyseCandidates(
      s.run, data, {}, fit,
      {Effect::kCrossQuadratic, Effect::kAngleLatency, Effect::kThermalDrift, Effect::kSizeEffect},
      o);
  int mixed = 0;
  for (const CandidateInformation& c : info.candidates) {
    SCOPED_TRACE(GetEffectSpec(c.effect).name);
    if (c.supported.empty()) continue;
    if (c.weak.empty()) {
      EXPECT_EQ(c.statistic_strong, c.statistic);
      EXPECT_EQ(c.p_value_strong, c.p_value);
    } else if (c.weak.size() < c.supported.size()) {
      ++mixed;
      EXPECT_LE(c.statistic_strong, c.statistic * (1.0 + 1e-9) + 1e-9);
      EXPECT_GE(c.p_value_strong, 0.0);
    }
    for (const auto& [q, information] : c.weak) EXPECT_LT(information, kMinInformationFound);
  }
  EXPECT_GE(mixed, 1);
}

}  // namespace
}  // namespace triadcal

// Closing the loop (docs/method.md): fit, look at the residuals, test every
// catalogue effect the model lacks, add the ones the data demand, refit, and
// report before and after.
//
// Screening (issue 12): every candidate is first scored from the current
// fit's linearisation alone (effect_information.h: the score test, which needs
// no refit). Only candidates whose score p-value is below refit_factor times
// the round's threshold, and whose score is close to the best one's
// (statistic - dof within 2 ln(refit_factor) of the best), are refitted for
// the likelihood ratio below, started at the score's Gauss-Newton step and
// with the effect parameters the score analysis found supported; the others
// keep their score statistic and p-value (they cannot be selected this round).
// A candidate whose one-step estimate (that step) is beyond its plausible
// range by more than twice its sigma is not refitted: it absorbs something
// else on that estimate (Plausibility, below), and "close to the best" is
// from the best of the others.
//
// Test of an effect E: the likelihood ratio of the fit with E added against the
// current model,
//   LR = 2 (cost_current - cost_with_E),
// scaled by the augmented fit's chi2/dof when that exceeds 1 (so a declared
// noise that is too small does not turn into false alarms), against chi2 with
// as many degrees of freedom as E has parameters the run supports. The
// augmented fit starts from the current solution with E's parameters at 0 and
// keeps the current model's held parameters held.
//
// Selection: forward, one effect per round. In each round every remaining
// candidate is tested and the smallest p-value is selected if it is below
// alpha / (number of candidates in the round) (Bonferroni: the chance of any
// false selection in a round stays below alpha). Rounds stop when nothing
// passes. Afterwards the residual is analysed again; structure that no
// candidate explained is reported with what it correlates with.
//
// Plausibility (issue 12): a candidate that passes only with a parameter
// beyond its plausible range (EffectSpec; its refit's, or its one-step
// estimate's when not refitted) absorbs something else: it is
// reported as such (DiagnosisResult::absorbing, and the residual is called
// unexplained), not selected, and not tested again; the next candidate of the
// round may be selected. Components of an effect that only a base parameter's
// prior or hold determine are held, not tested (effect_information.h).
// Candidates that explain the residual about as well as the selected one are
// listed as alternatives, and every selected effect's correlation with the
// base parameters is reported.
//
// With a gyro (SPEC section 10) every fit of the loop estimates the gyro
// block beside the accelerometer's parameters; the tests above are on the
// accelerometer's part (cost and score), which the gyro's parameters do not
// enter (docs/method.md section 6).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/model/effects.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/diagnosis/effect_information.h"
#include "solvers/diagnosis/residual_analysis.h"
#include "solvers/estimation/separability.h"
#include "solvers/estimation/batch_solver.h"

namespace triadcal {

struct DiagnoseOptions {
  // For every fit. The noise is estimated in every fit of the current model
  // and fixed at that fit's in the round's candidate refits; with
  // estimate_noise off the declared noise is kept throughout (noise-free
  // simulations whose yardstick is the declared noise).
  BatchOptions fit;
  double alpha = 0.01;  // family-wise false-selection rate per round
  int max_effects = 4;
  // Refit (likelihood ratio) the candidates whose score p-value is below
  // refit_factor x the round's threshold and close to the best (see above);
  // infinity refits every candidate.
  double refit_factor = 10.0;
  double power = 0.8;              // of the minimal detectable effects (could_hide)
  std::vector<Effect> candidates;  // empty: the whole catalogue (that the run can carry)
  std::function<void(const std::string&)> progress;
  // Estimated fraction done, 0..1: the first fit 0-0.15; each round (its
  // candidates' fits, then the refit if one is selected) 60 % of what is
  // left before 0.95, round 1 0.15-0.63 (rounds are not known in advance);
  // the closing residual analysis 0.95; within a fit, the fit's own
  // BatchOptions::fraction.
  std::function<void(double)> fraction;
};

struct CandidateTest {
  Effect effect;
  int round = 0;
  int dof = 0;             // effect parameters the run supports
  // 2 (cost_current - cost_with_effect), with a gyro plus the gyro's
  // 2 (nll_current - nll_with_effect) (effect_discovery.cpp TestRefit)
  double lr = 0.0;
  // the accelerometer's part / max(1, its chi2/dof of the augmented fit) + the gyro's
  double statistic = 0.0;
  double p_value = 1.0;    // of the LR when refit, else of the score statistic
  double threshold = 0.0;  // alpha / candidates in the round
  double score = 0.0;      // score (LM) statistic from the current fit, scaled as the LR
  double score_p_value = 1.0;
  // Refitted: the Wald statistic of the effect's free components against the
  // refit's reported covariance (honest for correlated residuals), and its
  // p-value. A candidate is selected only when this and p_value both pass.
  // Not refitted for its one-step Wald test (note): that test's, the model's
  // covariance with the considered parameters' prior uncertainty carried.
  double wald = 0.0;
  double wald_p_value = 1.0;
  // The degrees of freedom of that covariance (infinite for the model's;
  // about 1.5 E / S for the HAC one, bandwidth S over E epochs): the p-value
  // is Hotelling's (statistics.h).
  double wald_dof = 0.0;
  bool refit = false;  // lr, statistic, p_value from a refit (else from the score)
  // Not refitted for its one-step Wald test: wald, wald_p_value (and the
  // not_separable_ fields) are that test's.
  bool one_step_wald = false;
  bool selected = false;
  std::string note;                 // e.g. why it could not be tested
  double chi2_per_dof_after = 0.0;  // of the refit with the effect added (refit only)
  // Non-empty: the effect passes the test only with a size beyond its
  // plausible range (EffectSpec), so it absorbs something else and is not a
  // finding: which parameter, its value and the range.
  std::string absorbs;
  // Refitted, its likelihood ratio significant, and its Wald test too with
  // the considered parameters at nominal but not with their prior
  // uncertainty carried: the considered parameter that carries most of the
  // effect's variance in the refit (the effect is not separable from it on
  // this run), and that share; or the same of its one-step test when that
  // kept it from a refit. Empty otherwise.
  std::string not_separable_from;
  double not_separable_share = 0.0;
  double wald_p_given_consider = 1.0;  // the Wald test with the considered at nominal
};

// How a selected effect's parameters correlate with the base parameters in
// its fit: the base parameter each one correlates with most.
struct EffectCorrelation {
  std::string parameter;  // e.g. "angle_latency.tau"
  std::string with;       // e.g. "dz2"
  double rho = 0.0;
};

struct DiagnosisResult {
  ParameterLayout before_layout, after_layout;
  BatchResult before, after;
  ResidualReport before_residuals, after_residuals;
  std::vector<CandidateTest> ranking;  // first round, smallest p first
  std::vector<CandidateTest> tests;    // every test of every round
  std::vector<Effect> selected;
  // Every tested effect that was not selected, at the final fit: how large it
  // could be and go undetected, and what it would then do to the parameters
  // (largest max_shift_sigma first).
  std::vector<HideCase> could_hide;
  // Significant candidates that fit only with an implausible size (absorbs).
  std::vector<CandidateTest> absorbing;
  // Candidates that explain the residual about as well as the one selected in
  // their round (likelihood-ratio excess over dof within 2 ln 10, i.e. an
  // evidence ratio below 10), with their refit's chi2/dof.
  std::vector<CandidateTest> alternatives;
  std::vector<EffectCorrelation> correlations;  // of every selected effect, at the final fit
  double base_gradient_sigma = 0.0;             // effect_information.h's check, first round
  bool unexplained = false;                     // structure remains after the selection
  // Parameters of the final fit beyond 3 prior sigma from their nominal
  // values (separability.h): what the loop leaves for a missing effect, or
  // wrong nominal values, to explain; named in the verdict.
  std::vector<PriorExcursion> beyond_prior;
  std::vector<std::string> notes;               // e.g. candidates merged or skipped, and why
  std::string verdict;
};

DiagnosisResult Diagnose(const RunDescription& run, const RunData& data,
                         const DiagnoseOptions& options);

// The catalogue effects a run can carry (its data have what they need; a
// drift in time is left out when temp_C is linear in time, with a note), less
// those in `current`.
std::vector<Effect> CatalogueCandidates(const RunData& data, const std::vector<Effect>& current,
                                        std::vector<std::string>* notes);

// The could-hide list of a planned profile (issue 12: observability and design
// report it before any run): noise-free data of the profile fitted by the
// declared model started at theta (the truth: the fit reproduces the data),
// then Diagnose's reliability analysis of every candidate (options.candidates,
// or CatalogueCandidates) at the first round's threshold alpha / m. Depends on
// the profile and the declared noise, not on any noise draw.
std::vector<HideCase> CouldHideOnProfile(const RunDescription& run, const RunData& noise_free,
                                         const ParameterLayout& layout,
                                         const Eigen::VectorXd& theta,
                                         const DiagnoseOptions& options);

}  // namespace triadcal

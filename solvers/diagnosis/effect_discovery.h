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
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/model/effects.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/diagnosis/effect_information.h"
#include "solvers/diagnosis/residual_analysis.h"

namespace triadcal {

struct DiagnoseOptions {
  BatchOptions fit;            // for every fit (hold/free and the noise are managed here:
                               // the declared noise throughout, estimate_noise off)
  double alpha = 0.01;         // family-wise false-selection rate per round
  int max_effects = 4;
  // Refit (likelihood ratio) the candidates whose score p-value is below
  // refit_factor x the round's threshold and close to the best (see above);
  // infinity refits every candidate.
  double refit_factor = 10.0;
  double power = 0.8;          // of the minimal detectable effects (could_hide)
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
  int dof = 0;                 // effect parameters the run supports
  double lr = 0.0;             // 2 (cost_current - cost_with_effect)
  double statistic = 0.0;      // lr / max(1, chi2/dof of the augmented fit)
  double p_value = 1.0;        // of the LR when refit, else of the score statistic
  double threshold = 0.0;      // alpha / candidates in the round
  double score = 0.0;          // score (LM) statistic from the current fit, scaled as the LR
  double score_p_value = 1.0;
  bool refit = false;          // lr, statistic, p_value from a refit (else from the score)
  bool selected = false;
  std::string note;            // e.g. why it could not be tested
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
  double base_gradient_sigma = 0.0;    // effect_information.h's check, first round
  bool unexplained = false;            // structure remains after the selection
  std::vector<std::string> notes;      // e.g. candidates merged or skipped, and why
  std::string verdict;
};

DiagnosisResult Diagnose(const RunDescription& run, const RunData& data,
                         const DiagnoseOptions& options);

}  // namespace triadcal

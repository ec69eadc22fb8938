// What the current fit's linearisation says about every candidate effect,
// without refitting (issue 12): the score (Lagrange-multiplier) test of each
// effect, and the reliability of the model (Baarda; Teunissen's DIA) -- how
// large an effect could be and still go undetected, and how far it would then
// move the base parameters.
//
// Derivation. The batch cost is 0.5 |r(x, theta_b, theta_e)|^2 (whitened
// process and measurement residuals, priors, constraints; batch_solver.h).
// The current fit is its minimum over the states x and the base parameters
// theta_b with every candidate's parameters theta_e = 0. Linearising the
// problem with ALL candidates added, at that point, and eliminating the
// states by the Schur complement (schur_covariance.h) gives the information
// I over (theta_b, theta_e) of every candidate at once; the information of
// the problem with one candidate added is the sub-matrix over theta_b and
// that candidate's theta_e (the others held at 0 is exactly what leaving
// them out means). The gradient g = J^T r by theta_e at the fit (by x and
// theta_b it is zero there) gives the score statistic
//
//   S = g_e^T (I_ee - I_eb I_bb^-1 I_be)^-1 g_e,
//
// asymptotically equal to the likelihood ratio 2 (cost - cost_with_effect),
// and chi2 with k_e degrees of freedom under "no effect". As for the LR it is
// divided by the augmented fit's chi2/dof when that exceeds 1; here that is
// predicted, (2 cost - S) / (dof - k_e).
//
// Which of an effect's parameters the run supports is decided as the batch
// solver's hold policy does (pivoted Cholesky of the data information in prior
// units, keeping each with at least kMinInformationSupported),
// here conditional on the base parameters with their priors loosened 1e4
// times and the held ones released the same way: a component that only a
// base parameter's prior or hold determines (it rides on a direction the run
// does not determine) is held in the refit, not tested, and named with that
// parameter (leans_on).
//
// Reliability. An effect of size nabla (k_e-vector) makes the test statistic
// noncentral with lambda = nabla^T N nabla, N = I_ee - I_eb I_bb^-1 I_be (the
// data's part). It is detected with power beta at level alpha when
// lambda >= lambda0(alpha, beta, k_e) (statistics.h), so the minimal
// detectable effect along a unit direction c is sqrt(lambda0 / c^T N c), the
// largest along N's weakest eigenvector. Left in the data, it shifts the base
// estimate by dtheta_b = -I_bb^-1 I_be nabla (external reliability); over all
// nabla with lambda = lambda0 the largest shift of parameter j in its sigma is
//   sqrt(lambda0 b_j^T N^-1 b_j) / sigma_j,  b_j = row j of I_bb^-1 I_be.
// With a residual chi2/dof above 1 the statistics are divided by it, so
// lambda0 is multiplied by it.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/model/effects.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/estimation/batch_solver.h"

namespace triadcal {

// Below this information from the data (in units of the prior's) the run
// knows a component less than its prior does: its estimate is the prior's
// (observability's "unobservable", ObservabilityThresholds::unobservable),
// and it is not one the run can be said to find. (10, the fit's threshold for
// "not estimable", was tried: it also took the 29-mm size effect of the
// paper profile at 50 Hz for weak, whose components the data know to
// ~10 mm against a 20-mm prior, and rejected it in 20 of 20 seeds.)
constexpr double kMinInformationFound = 1.0;
// Below this (data information in prior units, given the base parameters) a
// candidate's component is not supported by the run at all: held at zero.
constexpr double kMinInformationSupported = 1e-2;

// The information of one candidate relative to the current model.
// A component of a candidate that the base parameters explain (|rho| >=
// 0.99): index into the effect's params, the base parameter it leans on most,
// and its multiple correlation with the base parameters.
struct NotSeparable {
  int component = 0;
  std::string with;
  double rho = 0.0;
};

struct CandidateInformation {
  Effect effect;
  std::vector<int> supported;    // indices into the effect's params the run supports
  std::vector<int> unsupported;  // the others but the not separable ones (held in a refit)
  // Supported by the data but not separable from the base parameters: not
  // tested, kept at zero in a refit with their prior uncertainty carried into
  // the others' sigma (considered, batch_solver.h).
  std::vector<NotSeparable> not_separable;
  // Why components are held although their information alone would let them
  // be tested: the axis never reverses (EffectNeeds::both_signs_per_axis), or
  // the data support them only through a base parameter's prior or hold
  // (LooseConditional in effect_information.cpp; e.g. scale_asymmetry.dKx on
  // Kx when the x axis only ever sees +g). Component index, reason.
  std::vector<std::pair<int, std::string>> held_because;
  // Supported components that the run determines too weakly to be found: their
  // information from the data (given the base parameters with their priors
  // loosened) is below kMinInformationFound times their prior's, where the
  // run knows them less than their prior does. They stay
  // free in a refit, under their priors: held at zero they would leave
  // whatever they stand for in the base parameters with sigma that do not
  // know it (a 6' outer-encoder harmonic then left Kxx and W0x 3-5 sigma off
  // in 18 of 20 seeds, against 4 of 20 with them free); diagnose names them
  // in a note. Index, information.
  std::vector<std::pair<int, double>> weak;
  // The score test of the components the run determines well (the supported
  // ones not weak; weak ones left out) and its p-value, scaled as
  // `statistic`: an effect significant only through its weak components is
  // not a finding (diagnose reports it as absorbing something else).
  double statistic_strong = 0.0;
  double p_value_strong = 1.0;
  double score = 0.0;      // S (unscaled)
  double statistic = 0.0;  // S / max(1, predicted chi2/dof)
  double p_value = 1.0;
  // Conditional data information N over the supported params (SI), given
  // the free base parameters and with the considered ones' prior uncertainty
  // carried (as in the refit's covariance), and the base-parameter coupling
  // B = I_bb^-1 I_be (free base rows x supported).
  Eigen::MatrixXd N, B;
  // The Gauss-Newton step from the current fit to the fit with the effect
  // added (base free parameters, then the supported ones; SI), a start for
  // its refit.
  Eigen::VectorXd step_base, step_effect;
  // The refit's Wald test in one step: step_effect against the refit's
  // covariance to first order, the model's (white) one: the inverse of the
  // conditional information with the candidate's prior, plus the consider
  // term (wald_one_step), or without it, the considered parameters at
  // nominal (wald_one_step_given); the considered parameter that carries most
  // of the effect's variance there and that share (as the refit's,
  // effect_discovery.cpp; empty without considered parameters). Where the
  // residual is correlated the refit's sigma are the HAC ones, floored at the
  // model's: its test is no easier than this one.
  double wald_one_step = 0.0, wald_one_step_given = 0.0;
  std::string most_considered;
  double most_considered_share = 0.0;
};

struct EffectInformation {
  std::vector<std::string> base_names;  // the free base parameters (rows of B)
  Eigen::VectorXd base_sigma;           // their sigma in the current model (SI)
  double chi2_per_dof = 1.0;            // of the current fit
  std::vector<CandidateInformation> candidates;
  // |g| over the base parameters in units of their sigma: ~0 at the current
  // fit's optimum (a check that the linearisation is the fit's).
  double base_gradient_sigma = 0.0;
};

// Linearises the run with `current` effects and every candidate added at the
// current fit (theta in the layout of `current`, held parameters as in
// fit.held) and computes each candidate's score test and information.
EffectInformation AnalyseCandidates(const RunDescription& run, const RunData& data,
                                    const std::vector<Effect>& current, const BatchResult& fit,
                                    const std::vector<Effect>& candidates,
                                    const BatchOptions& options);

// Reliability of the current model against one candidate (see above).
struct HideCase {
  Effect effect;
  double alpha = 0.0, power = 0.8, lambda0 = 0.0;
  // The minimal detectable effect along its weakest direction, in the
  // effect's file units: its length and its components (supported params).
  double minimal_detectable = 0.0;
  std::string unit;
  std::vector<std::pair<std::string, double>> direction;
  // The largest shift of any free base parameter by an undetected effect
  // (lambda <= lambda0), in its sigma, and that parameter.
  double max_shift_sigma = 0.0;
  std::string parameter;
  std::vector<std::string> undetectable;  // params the run's motion cannot see at all
};
HideCase MinimalDetectable(const EffectInformation& info, const CandidateInformation& c,
                           double alpha, double power);

}  // namespace triadcal

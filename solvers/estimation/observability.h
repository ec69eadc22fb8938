// Observability of a run: the Cramer-Rao bound of theta and the directions the
// run cannot determine, from the Fisher information of the batch model
// (docs/method.md) -- the same linearisation the estimators use.
//
// Fisher information. run_evaluation.h evaluates every process (B1) and
// measurement (B2) of the run at a theta and eliminates the trajectory
// exactly (the same reduction the batch solver steps with); what is left is
// I_data, the information of the data alone about theta. Every variant below
// reuses it: with the constraints c_j . theta = v_j +- s_j, P = diag(prior
// sigma^2),
//
//   I_V   = I_data + sum_{j in V} c_j c_j^T / s_j^2     (data + constraints)
//   CRB_V = (I_V + P^-1)^-1                               (what an estimator reports)
//
// Directions. In prior units (theta_i / prior sigma_i, D = diag(prior sigma))
// the eigenvalues lambda of D I_V D are the information the run gives along
// each eigenvector, against 1 for the prior; 1/sqrt(lambda) prior sigma is
// what the data alone determine along it. With the thresholds of
// ObservabilityThresholds:
//
//   lambda < unobservable          unobservable: the answer along it is the
//                                  prior's (a structural null of the model has
//                                  lambda ~ 1e-6, rounding; see docs/method.md)
//   lambda < weak                  weakly observable: determined, but the
//                                  prior still shapes the answer
//
// The unobservable subspace is returned in reduced row-echelon form (each
// direction led by one parameter, zero on the others' leaders), so that a
// several-dimensional null space reads as a few simple combinations instead of
// arbitrary eigenvector mixtures. Each direction names its parameters (weight
// >= 0.2 in prior units) and is described in words (separability.h).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/parameters.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "core/model/priors.h"
#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/separability.h"

namespace triadcal {

// Information along a direction, in prior units (1 = as much as the prior).
struct ObservabilityThresholds {
  // Below: the data determine it less well than the prior (data sigma along it
  // above the prior sigma).
  double unobservable = 1.0;
  // Below: weakly observable (data sigma above 0.1 prior sigma).
  double weak = 100.0;
};

// A direction of theta with the information the run gives along it.
struct Direction {
  WeakDirection named;        // weights (prior units), description, information
  Eigen::VectorXd v_prior;    // unit vector in prior units (n)
  // What the data (with the variant's constraints, without the priors) give
  // along it, per parameter in SI: |v_i| prior_sigma_i / sqrt(lambda); empty
  // for an unobservable direction.
  Eigen::VectorXd data_sigma;
};

// One set of constraints in force.
struct ObservabilityVariant {
  std::string name;                      // "with constraints", "without constraints", ...
  std::vector<std::string> constraints;  // exprs in force
  std::string dropped;                   // without_each: the constraint left out
  Eigen::MatrixXd information;           // I_V (SI), data + these constraints, no priors
  Eigen::MatrixXd cov;                   // CRB_V (SI), with the priors
  Eigen::VectorXd eigenvalues;           // of D I_V D, ascending
  std::vector<Direction> unobservable, weak;
};

struct ObservabilityResult {
  ParameterLayout layout;
  Eigen::VectorXd theta;   // evaluation point (SI)
  Prior prior;
  Eigen::MatrixXd data_information;  // I_data (SI): no priors, no constraints
  ObservabilityVariant with_constraints;     // all constraints of the run
  ObservabilityVariant without_constraints;  // none
  std::vector<ObservabilityVariant> without_each;  // all but constraint j (one per constraint)
  std::size_t samples = 0, epochs = 0;
  double duration_s = 0.0;
  double seconds = 0.0;
};

struct ObservabilityOptions {
  ObservabilityThresholds thresholds;
  int threads = 0;  // 0: all cores
};

// I_data at theta for the run of p (SI): one linearisation pass over the
// samples and one Schur elimination of the trajectory; with a gyro triad in
// the layout and the run, its increments' information (gyro_term.h) at
// p.gyro_noise_rad_s as well.
Eigen::MatrixXd DataInformation(const RunProblem& p, const Eigen::VectorXd& theta, int threads);

// The whole analysis for the run of p (built from run) at theta.
ObservabilityResult AnalyseObservability(const RunDescription& run, const RunProblem& p,
                                         const Eigen::VectorXd& theta,
                                         const ObservabilityOptions& opt = {});

// The variant for one set of constraint rows, from I_data.
ObservabilityVariant MakeVariant(const ParameterLayout& layout, const Eigen::MatrixXd& data_info,
                                 const Prior& prior, const std::vector<ConstraintRow>& rows,
                                 const std::vector<std::string>& exprs, const std::string& name,
                                 const ObservabilityThresholds& t);

// Directions of an information matrix (SI, no priors) in prior units:
// unobservable (row-echelon basis of the subspace, in the layout's order of
// each direction's main parameter: the first with at least half its largest
// weight) and weakly observable (eigenvectors), as defined above.
void ClassifyDirections(const ParameterLayout& layout, const Eigen::MatrixXd& information,
                        const Eigen::VectorXd& prior_sigma, const ObservabilityThresholds& t,
                        std::vector<Direction>* unobservable, std::vector<Direction>* weak);

// For fit and filter: the directions this run (data and constraints) cannot
// determine, i.e. the unobservable ones of the analysis above, at theta (the
// estimate). Costs one linearisation pass over the samples and a Schur
// elimination (about what one relinearisation of the batch solver costs).
std::vector<WeakDirection> UnsupportedDirections(const RunProblem& p, const Eigen::VectorXd& theta,
                                                 const ObservabilityThresholds& t = {});

// The same from an estimator's posterior covariance (which holds the data, the
// constraints and the priors): I = cov^-1 - P^-1. Free (an n x n eigen-
// decomposition); what fit and filter can call on their own covariance.
std::vector<WeakDirection> UnsupportedDirections(const ParameterLayout& layout,
                                                 const Eigen::MatrixXd& posterior_cov,
                                                 const Eigen::VectorXd& prior_sigma,
                                                 const ObservabilityThresholds& t = {});

}  // namespace triadcal

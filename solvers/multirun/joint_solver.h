// The joint fit of several runs of one IMU (docs/multi-run.md).
//
// 1. Each run is fitted alone (SolveBatch): its own estimate, what it
//    determines, its reading noise (estimated with its parameters) and
//    whether its residuals are white.
// 2. The unknowns phi (joint_layout.h) that the runs together do not
//    determine are decided before the joint fit by the rule of a single fit
//    (SupportedByInformation) on the combined information sum_r T_r^T I_r T_r
//    at the nominal values plus the constraints: structural nulls held, the
//    rest kept at nominal and considered (their prior uncertainty carried).
// 3. The one minimiser of the batch problem (batch_minimizer.h) over phi and
//    every run's noise: the sum of the runs' likelihoods (each trajectory
//    solved for at every step), the priors once, each run's constraints.
// 4. The covariance keeps each run's own view of its data: the model's
//    information for a run with white residuals, its own HAC estimate over its
//    own epochs for one without (hac_covariance.h), floored at the model's;
//    the consider term; and, per shared unknown that at least two runs
//    determine alone, the spread between the runs (BetweenRuns, random
//    effects): when the runs disagree beyond their sigma (Cochran's Q, p <
//    between_alpha), the joint sigma carries that spread, and the output
//    names the unknown.
// 5. Consistency: each run's score (its gradient at the joint solution) over
//    the parameters it determines alone, against its variance if the runs
//    agree, I_r - I_r T_r Sigma_J T_r^T I_r: the part of run r's information
//    the joint solution did not absorb (a score form of the Hausman test of
//    the run's own estimate against the joint one; at the joint solution,
//    so the values at which the run alone held its undetermined parameters
//    do not enter). chi2 over the directions with at least 1e-3 of the run's
//    own information left, their number the degrees of freedom; a run with
//    p < consistency_alpha is named, with the parameters it pulls (|z| >= 3).
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/batch_solver.h"
#include "solvers/multirun/joint_layout.h"

namespace triadcal {

struct JointOptions {
  // Epochs, derivatives, threads, hold policy, noise estimation, progress:
  // for the runs fitted alone and for the joint problem.
  BatchOptions batch;
  int max_iterations = 40;
  // Converged when the predicted decrease of the cost (0.5 chi^2) of the next
  // step is below this: a step of ~0.01 sigma.
  double tolerance = 1e-4;
  double consistency_alpha = 1e-3;
  // Cochran's Q test of a shared unknown over the runs that determine it
  // alone: below this p the runs disagree on it, and the joint sigma carries
  // their spread (BetweenRuns). Not applied to every Q above its dof (the
  // DerSimonian-Laird estimate alone): with two or three runs tau^2 is
  // positive for half the unknowns of agreeing runs, and sigma came out
  // sqrt(Q) = up to 2.2x too large on them (JointFit test of two runs).
  double between_alpha = 0.05;
};

struct RunConsistency {
  bool tested = false;
  double chi2 = 0.0;
  int dof = 0;
  double p_value = 1.0;
  bool consistent = true;
  // Joint parameter names (IMU axes) and the score z of each, |z| >= 3,
  // largest first (z > 0: the run alone would put it below the joint value).
  std::vector<std::pair<std::string, double>> pulls;
  // Every compared parameter, in the run's layout (platform axes): z.
  std::vector<std::pair<std::string, double>> z;
};

// The between-run component of one shared unknown (DerSimonian-Laird random
// effects over the runs that determine it alone): Cochran's Q of their own
// estimates against their precision-weighted mean, tau the spread between
// them beyond their sigma (SI), and, where they disagree, the factor it puts
// on the joint sigma, sqrt(1 + tau^2 sum_r share_r^2 / sigma^2) (1 otherwise).
struct BetweenRuns {
  int index = -1;   // into phi
  int runs = 0;     // runs that determine it alone
  double q = 0.0;
  int dof = 0;
  double p_value = 1.0;
  bool disagree = false;  // p < between_alpha: the spread is in the joint sigma
  double largest_z = 0.0;  // the farthest run from the mean, in its own sigma
  double tau = 0.0;
  double sigma_factor = 1.0;
};

struct JointRunResult {
  std::string name;
  BatchResult alone;               // the run fitted alone
  Eigen::Vector3d noise_mV = Eigen::Vector3d::Zero();  // used for this run
  Eigen::VectorXd theta;           // its parameters at the joint solution (run layout)
  double chi2_per_dof = 0.0;       // of its residuals at the joint solution
  int degrees_of_freedom = 0;
  RunConsistency consistency;
  std::string sigma_method = "white";  // its data's part of the covariance: white or hac
  double hac_bandwidth_epochs = 0.0;
};

struct JointResult {
  Eigen::VectorXd phi;     // all joint unknowns (SI); held ones at nominal
  Eigen::MatrixXd cov;     // zero rows and columns for the held and considered ones
  Eigen::MatrixXd cov_white;  // the model's, with the consider term, before the runs' HAC and spread
  std::vector<int> held;      // structural nulls: held at nominal (indices into phi)
  std::vector<int> consider;  // not determined: nominal, prior uncertainty carried
  // Estimated unknowns the runs determine only with the considered ones at
  // nominal (DeterminedOnlyWithConsidered, batch_solver.h): index -> the
  // considered unknowns that carry most of their sigma (indices into phi).
  std::map<int, std::vector<int>> with_considered;
  std::vector<BetweenRuns> between;  // each shared unknown at least two runs determine alone
  std::vector<JointRunResult> runs;
  // share(r, j): run r's part of the data information on phi_j (diagonal).
  Eigen::MatrixXd share;
  // Shared unknowns the runs determine together that no run determines alone.
  std::vector<std::string> jointly_only;
  double cost = 0.0, chi2_per_dof = 0.0;
  int degrees_of_freedom = 0, iterations = 0;
  bool converged = false;
  std::string termination;  // why the minimiser stopped (batch_minimizer.h)
  double seconds_alone = 0.0, seconds_joint = 0.0;
};

// What the runs together determine, without fitting (observability of
// several runs): the Fisher information of the joint unknowns at their
// nominal values for each run's declared noise, the hold rule's decision on
// it, each run's share, and what no run determines alone (each run's own hold
// rule at the nominal values).
struct JointInformation {
  Eigen::MatrixXd information;  // m x m: data, constraints and priors
  Eigen::MatrixXd cov;          // m x m: the Cramer-Rao bound over the free unknowns, zero for held
  std::vector<int> held;        // indices into phi
  Eigen::MatrixXd share;        // R x m, as JointResult::share
  std::vector<std::vector<std::string>> held_alone;  // per run, its layout's names
  std::vector<std::string> jointly_only;
};
JointInformation JointInformationAtNominal(const std::vector<JointRun>& runs,
                                           const JointLayout& layout,
                                           const JointOptions& options);

// Throws InputError/OptionError for bad settings; runtime_error when a run
// alone cannot be fitted.
JointResult SolveJoint(const std::vector<JointRun>& runs, const JointLayout& layout,
                       const JointOptions& options);

}  // namespace triadcal

// The batch problem linearised at one theta, without solving it: the B1
// increments of every interval with their Jacobians, the whitening of every
// process and measurement residual, and the rows of the priors and
// constraints. The batch solver builds its Ceres problem from it; the
// observability analysis turns it into the Fisher information of theta
// (schur_covariance.h) for any run, recorded or simulated.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/batch_costs.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

struct BatchLinearization {
  Eigen::VectorXd theta_lin;
  std::vector<IntervalIncrement> increments;  // E - 1
  std::vector<Mat6> LQ;                       // E - 1 process whitenings
  std::vector<Mat6> LR;                       // E measurement whitenings
};

// with_jacobian = false leaves the increment Jacobians empty (exact mode).
BatchLinearization Linearize(const RunProblem& p, const Eigen::VectorXd& theta,
                             bool with_jacobian, int threads);

// Rows over theta alone, whitened: the priors (n rows) and, when asked, the
// constraints; A theta - b is their residual.
void ThetaRows(const RunProblem& p, bool with_constraints, Eigen::MatrixXd* A,
               Eigen::VectorXd* b);

// Covariance of theta (the inverse of the Fisher information with the priors,
// and the constraints when they are in A) from the Jacobians of the
// linearisation, with the B2 Jacobians evaluated at theta. This is the
// Cramer-Rao bound of the model at theta for the run's motion and timing.
Eigen::MatrixXd ThetaCovariance(const RunProblem& p, const BatchLinearization& lin,
                                const Eigen::VectorXd& theta, const Eigen::MatrixXd& A,
                                int threads);

}  // namespace triadcal

// The batch problem linearised at one theta, without solving it: every
// interval's process step (state_space_model.h) with its Jacobian, the
// whitening of every process and measurement residual, and the rows of the
// priors and constraints, all over the free parameters of the problem. The
// batch solver builds its Ceres problem from it; the observability analysis
// turns it into the Fisher information of theta (schur_covariance.h) for any
// run, recorded or simulated.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/schur_covariance.h"
#include "solvers/estimation/state_space_model.h"

namespace triadcal {

struct BatchLinearization {
  Eigen::VectorXd theta_lin;        // all n parameters
  Eigen::VectorXd theta_lin_free;   // the free ones
  std::vector<ProcessStep> process;  // E - 1
  std::vector<Mat6> LQ;              // E - 1 process whitenings
  std::vector<Mat6> LR;              // E measurement whitenings
};

// with_jacobian = false leaves the process Jacobians empty (exact mode).
BatchLinearization Linearize(const RunProblem& p, const Eigen::VectorXd& theta,
                             bool with_jacobian, int threads);

// Rows over the free parameters alone, whitened: the priors and, when asked,
// the constraints; A theta_free - b is their residual.
void ThetaRows(const RunProblem& p, bool with_constraints, Eigen::MatrixXd* A,
               Eigen::VectorXd* b);

// The whitened Jacobian blocks of the linearisation (schur_covariance.h), with
// the B2 Jacobians at theta; r0 is left zero. process_theta_jacobians: as in
// ThetaCovariance below.
void SchurBlocks(const RunProblem& p, const BatchLinearization& lin, const Eigen::VectorXd& theta,
                 int threads, const std::vector<Eigen::MatrixXd>* process_theta_jacobians,
                 std::vector<ProcessBlock>* pb, std::vector<MeasurementBlock>* mb);

// Covariance of the free parameters (the inverse of the Fisher information
// with the priors, and the constraints when they are in A) from the Jacobians
// of the linearisation, with the B2 Jacobians evaluated at theta. This is the
// Cramer-Rao bound of the model at theta for the run's motion and timing.
// process_theta_jacobians, when given, are the whitened d r_p / d theta_free
// of each interval at the solution (the batch's process costs, which include
// the derivative of the whitening by the scale factors) in place of -L_Q U.
Eigen::MatrixXd ThetaCovariance(const RunProblem& p, const BatchLinearization& lin,
                                const Eigen::VectorXd& theta, const Eigen::MatrixXd& A,
                                int threads,
                                const std::vector<Eigen::MatrixXd>* process_theta_jacobians = nullptr);

// The free-parameter covariance placed in an n x n matrix (zero rows and
// columns for the held parameters).
Eigen::MatrixXd ExpandCovariance(const RunProblem& p, const Eigen::MatrixXd& cov_free);

// The autocorrelation at lags 1..lags that the whitened process residuals
// (6 channels) have at a least-squares solution even when the model holds:
// r = (I - H) w with H(t, u) = j_t^T cov j_u, j_t the whitened residual's
// derivative by the free parameters (C[t], 6 x n_free) and cov their
// covariance; rho_k = -sum_t H(t, t+k) / sum_t (1 - H(t, t)). Smooth
// regressors make it negative at short lags, about -(parameters a channel
// carries) / (epochs); the whiteness tests subtract it.
std::array<std::vector<double>, 6> ExpectedProcessAutocorrelation(
    const std::vector<Eigen::MatrixXd>& C, const Eigen::MatrixXd& cov_free, int lags);

}  // namespace triadcal

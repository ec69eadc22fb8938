// One run's batch cost as a function of theta alone, its trajectory solved
// for (variable projection): what a problem over several runs
// (solvers/multirun/) adds up, run by run.
//
// At theta the run is linearised (batch_linearization.h) and its process and
// measurement costs (batch_costs.h, the very residuals of the batch solver)
// are evaluated at x = 0 with their Jacobians. The residuals are affine in
// the states for this theta, so eliminating the states (ReduceOverStates,
// schur_covariance.h) gives the cost at the optimal trajectory, its gradient
// by theta and the Gauss-Newton information. The priors and constraints are
// not included: the caller adds them once.
//
// At a converged single-run fit the gradient is zero and the information plus
// the priors' is the inverse of the fit's covariance (reduced_run_test.cpp).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/run_problem.h"

namespace triadcal {

struct ReducedRun {
  double cost = 0.0;            // 0.5 chi^2 of the process and measurement residuals
  Eigen::VectorXd gradient;     // by the free parameters of the problem
  Eigen::MatrixXd information;  // over the free parameters
  // Degrees of freedom of these residuals with the states solved for: 6 per
  // interval (the measurements only fix the states); constraints not counted.
  int degrees_of_freedom = 0;
  std::vector<Eigen::Matrix<double, 6, 1>> states;  // optimal (V, S) per epoch, when asked
};

ReducedRun ReduceRun(const RunProblem& p, const Eigen::VectorXd& theta, int threads,
                     bool with_states = false);

// Levenberg-Marquardt on theta alone over the reduced cost plus the priors
// and constraints (StateSpaceModel::ThetaRows): Gauss-Newton on the exact
// nonlinear problem, one linearisation of the run per iteration. The batch
// solver finishes with it when relinearising converges only linearly.
// Returns the free parameters; *converged when the predicted decrease of the
// last step fell below tolerance (0.5 chi^2 units).
Eigen::VectorXd MinimiseReducedCost(const RunProblem& p, const Eigen::VectorXd& theta_free,
                                    int threads, int max_iterations, double tolerance,
                                    bool* converged, int* iterations,
                                    const std::function<void(const std::string&)>& say = nullptr);

}  // namespace triadcal

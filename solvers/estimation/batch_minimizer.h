// The one solver of the batch problem: Levenberg-Marquardt on the parameters
// (the free unknowns of a BatchObjective), every run's trajectory solved for
// exactly at every evaluation, and each run's reading noise at its maximum
// likelihood at every accepted point.
//
// The unknowns of a step are z = (the free parameters, s = log sigma of each
// channel of every run whose noise is estimated), and the function is the
// negative log-likelihood -log L = cost(theta, s) + rho 0.5 sum log det Q(s)
// (run_evaluation.h). Its gradient is exact; its Hessian is the Gauss-Newton
// information in theta, 2 q_i in s_i and -2 g_i between them (g_i: channel
// i's share of the gradient): a step moves the parameters and the noise
// together, as they are coupled (a parameter that changes a channel's
// residual changes its noise estimate, and the noise the channels' weights).
//
// The steps, in the order Minimize takes them (after Ceres's
// TrustRegionMinimizer: the state lives in members, each step is named):
//
//   IterationZero     evaluate at the start (one pass over the samples) and
//                     put each estimated noise at its maximum there
//                     (variance components; reductions only)
//   ComputeStep       converged when the Newton decrement 0.5 g^T H^-1 g
//                     (~0.5 |step|^2 in sigma units) is below the tolerance;
//                     else the damped step (B + mu diag H) d = -g, B = H plus
//                     the curvature the last step measured
//   TryStep           evaluate the trial (one pass); accept it when -log L
//                     fell (damping by Nielsen's rule on the gain ratio),
//                     else raise the damping
//   MeasureCurvature  the curvature of -log L along the accepted step against
//                     the model's: a misfit's residual curvature makes
//                     Gauss-Newton converge linearly, the rank-one correction
//                     restores the step length along the slow direction
//
// The answer is the joint maximum of the likelihood in theta and the noises,
// whatever the path: the exact increments are evaluated at every trial point
// and the convergence test is on the exact gradient. A run that does not
// converge says why (termination).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/batch_objective.h"

namespace triadcal {

struct MinimizerOptions {
  int max_iterations = 40;
  // Converged when the Newton decrement is below this (0.5 chi^2 units): a
  // step of sqrt(2 tolerance) sigma, 0.014 sigma at 1e-4.
  double tolerance = 1e-4;
  // Per run: estimate its reading noise (else it stays at its start).
  std::vector<bool> estimate_noise;
  std::function<void(const std::string&)> progress;
  std::function<void(double)> fraction;  // 0..1 along the iterations (estimated)
};

struct MinimizerSummary {
  bool converged = false;
  std::string termination;  // why it stopped, in words
  int iterations = 0;       // trial steps evaluated
  int accepted = 0;
  int passes = 0;           // passes over the samples
  double initial_cost = 0.0, final_cost = 0.0;
  double newton_decrement = 0.0;  // at the end
};

class BatchMinimizer {
 public:
  BatchMinimizer(const BatchObjective& objective, std::vector<int> free, MinimizerOptions options);

  // From phi0 (all m unknowns; those not free stay) and each run's starting
  // noise. Returns the final point (with the Jacobian, at the final noises).
  BatchObjective::Point Minimize(const Eigen::VectorXd& phi0,
                                 const std::vector<Eigen::Vector3d>& noise0,
                                 MinimizerSummary* summary);

  const std::vector<Eigen::Vector3d>& noise() const { return noise_; }
  // The unknowns that move run r's parameters (the fitted count of its noise estimate).
  int FittedFor(int r) const;

 private:
  void IterationZero(const Eigen::VectorXd& phi0);
  // False when converged (or stopped: summary_.termination says why).
  bool ComputeStep();
  bool TryStep();
  void MeasureCurvature(const BatchObjective::Point& trial);
  void Say(const std::string& line) const;
  // -log L up to a constant: the cost and each estimated noise's
  // log-determinant (run_evaluation.h).
  double Objective(const BatchObjective::Point& pt) const;
  // Its gradient and Hessian over z = (the free unknowns, log sigma of each
  // noisy run's channels): the Gauss-Newton information, the noise's
  // curvature 2 q_i, and their coupling -2 g_i (run_evaluation.h).
  void Model(const BatchObjective::Point& pt, Eigen::VectorXd* g, Eigen::MatrixXd* H) const;
  double NoiseFloor(int run, int channel) const;
  // The noises of the runs that estimate them at their maximum at pt.
  void MaximiseNoise(BatchObjective::Point* pt, std::vector<Eigen::Vector3d>* noise) const;

  const BatchObjective& objective_;
  std::vector<int> free_;
  MinimizerOptions options_;
  std::vector<int> noisy_;      // the runs whose noise is estimated
  std::vector<double> rho_;     // their restricted-likelihood share (run_evaluation.h)
  MinimizerSummary summary_;
  std::vector<Eigen::Vector3d> noise_;
  BatchObjective::Point current_;
  Eigen::VectorXd step_;       // over z
  Eigen::MatrixXd secant_;     // the last step's curvature correction over z
  double predicted_ = 0.0;     // decrease the damped step predicts
  double mu_ = 1e-8, nu_ = 2.0;
};

}  // namespace triadcal

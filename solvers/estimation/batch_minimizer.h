// The one solver of the batch problem: Levenberg-Marquardt on the parameters
// (the free unknowns of a BatchObjective), every run's trajectory solved for
// exactly at every evaluation, and each run's reading noise at its maximum
// likelihood at every point evaluated.
//
// The function is the negative log-likelihood -log L = cost(theta, s) +
// rho 0.5 sum log det Q(s) (run_evaluation.h), s = log sigma of each channel
// of every run whose noise is estimated. Every point the minimiser evaluates
// has its noise at its maximum there (MaximiseNoise: variance components,
// reductions only), so the steps are on the likelihood profiled over the
// noise, in theta alone; its gradient there is the exact gradient in theta
// (the noise's part vanishes at its maximum).
//
// The step's model is Gauss-Newton's information plus a correction S that
// the steps taken measure (MeasureCurvature, a structured BFGS update as in
// NL2SOL): a misfit's residuals curve the cost beyond Gauss-Newton's model.
// Near the minimum it is also profiled over the noise: with G = d gradient /
// d log sigma and H_ss the noise's Hessian, -log L's Hessian in theta loses
// G H_ss^-1 G^T (FormCoupling; the real fast roll run converged linearly
// without it, 8 steps, superlinearly with it, 6). The noise's exponential
// makes that model err at third order far from the minimum, where a misfit
// makes G large and the coupled model promise what the cost does not give
// (an earlier form of the coupling, taken at every step of the paper's
// 90-s 1-kHz run from the RTS start: five steps rejected, 9 steps in 15
// passes; 2 in 3 at fixed noise). So it
// is taken only while the Gauss-Newton decrement is within
// CoupledModelReach, the model at fixed noise beyond.
//
// The steps, in the order Minimize takes them (after Ceres's
// TrustRegionMinimizer: the state lives in members, each step is named):
//
//   IterationZero     evaluate at the start (one pass over the samples) and
//                     put each estimated noise at its maximum there
//                     (variance components; reductions only)
//   ComputeStep       converged when the Newton decrement of the profile
//                     0.5 g^T (H - C)^-1 g (~0.5 |step|^2 in sigma units; C
//                     the coupling) is below the tolerance; else the damped
//                     step (B + mu diag H) d = -g, B = H + S (- C near the
//                     minimum)
//   TryStep           evaluate the trial (one pass); accept it when -log L
//                     fell (damping by Nielsen's rule on the gain ratio),
//                     else raise the damping (RaiseDamping: to the step's
//                     length a parabola along the refused one gives)
//   MeasureCurvature  the change of the gradient along the accepted step, at
//                     fixed noise, into S (BFGS on H + S)
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
  // Unknowns whose gradient and information every step forms with the free
  // ones' (and whose blocks it keeps): a fit's considered parameters, which
  // its covariance's consider term reads at the minimum.
  std::vector<int> also_formed;
  // The point returned with its gradient and information by every unknown
  // (one reduction more: the steps form them by the free ones and
  // also_formed alone), its reductions' blocks kept; else by those.
  bool full_information = true;
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
  // noise. Returns the final point (with the Jacobian, at the final noises;
  // options.full_information says by which unknowns).
  BatchObjective::Point Minimize(const Eigen::VectorXd& phi0,
                                 const std::vector<Eigen::Vector3d>& noise0,
                                 MinimizerSummary* summary);

  const std::vector<Eigen::Vector3d>& noise() const { return noise_; }
  // The unknowns that move run r's parameters (the fitted count of its noise estimate).
  int FittedFor(int r) const;

 private:
  void IterationZero(const Eigen::VectorXd& phi0);
  // What a new point's reductions form: in full only when no noise is
  // estimated (else MaximiseNoise forms them at the noise's maximum).
  ThetaPart FullUnlessNoisy() const;
  // False when converged (or stopped: summary_.termination says why).
  bool ComputeStep();
  bool TryStep();
  // After a refused step that raised -log L by `rise` (not finite: unknown).
  void RaiseDamping(double rise);
  // The damped step (B + mu diag(scale)) d = -g; false in *ok when that
  // matrix is not positive definite.
  Eigen::VectorXd DampedStep(const Eigen::MatrixXd& B, const Eigen::VectorXd& g,
                             const Eigen::VectorXd& scale, double mu, bool* ok) const;
  // The model's matrix B = H + S (less coupling_ with couple_) and the
  // damping's scale |diag H| at the current point.
  void DampingModel(const Eigen::MatrixXd& H, Eigen::MatrixXd* B, Eigen::VectorXd* scale) const;
  // step_ and predicted_ from the model at the current point (gradient g,
  // Gauss-Newton's H), the damping raised until it is positive definite and
  // predicts a decrease; false (termination said) when none does.
  bool DampedModelStep(const Eigen::VectorXd& g, const Eigen::MatrixXd& H);
  // The Gauss-Newton decrement up to which a step takes the coupled model
  // (the noise's third-order error within the tolerance).
  double CoupledModelReach() const;
  // Profiling a run's estimated noise couples it to theta: with G = d
  // gradient / d log sigma (RunReduction::gradient_by_log_noise, in the free
  // unknowns) and H_ss its noise's Hessian (NoiseHessian), -log L's Hessian
  // loses G H_ss^-1 G^T. coupling_ at pt: that sum over the runs whose noise
  // is estimated and at a maximum (empty with none).
  void FormCoupling(const BatchObjective::Point& pt);
  // The current point's gradient in the free unknowns at the trial's noise
  // (the current point reweighted: a reduction, no pass; none when the noise
  // did not move), before the trial's theta part is formed (one point's
  // blocks held at a time).
  Eigen::VectorXd GradientAtTrialNoise(const BatchObjective::Point& trial,
                                       const std::vector<Eigen::Vector3d>& trial_noise) const;
  // g0: GradientAtTrialNoise.
  void MeasureCurvature(const BatchObjective::Point& trial, const Eigen::VectorXd& g0);
  void Say(const std::string& line) const;
  // -log L up to a constant: the cost and each estimated noise's
  // log-determinant (run_evaluation.h).
  double Objective(const BatchObjective::Point& pt) const;
  // Its gradient in the free unknowns and their Gauss-Newton information.
  void Model(const BatchObjective::Point& pt, Eigen::VectorXd* g, Eigen::MatrixXd* H) const;
  double NoiseFloor(int run, int channel) const;
  // The noises of the runs that estimate them at their maximum at pt, its
  // reductions formed there with theta_part (with kNone they may stay at
  // the noise before Newton's last step, within kLastNoiseStep).
  void MaximiseNoise(BatchObjective::Point* pt, std::vector<Eigen::Vector3d>* noise,
                     ThetaPart theta_part) const;

  const BatchObjective& objective_;
  std::vector<int> free_;
  // free_ and options_.also_formed, sorted: what a step's reductions form.
  std::vector<int> formed_;
  MinimizerOptions options_;
  std::vector<int> noisy_;      // the runs whose noise is estimated
  std::vector<double> rho_;     // their restricted-likelihood share (run_evaluation.h)
  MinimizerSummary summary_;
  Eigen::MatrixXd coupling_;             // at the current point (FormCoupling)
  bool couple_ = false;                  // the step's model is profiled over the noise
  std::vector<Eigen::Vector3d> noise_;
  BatchObjective::Point current_;
  Eigen::VectorXd step_;       // over the free unknowns
  Eigen::MatrixXd secant_;     // S: the curvature beyond Gauss-Newton the steps measured
  double predicted_ = 0.0;     // decrease the damped step predicts
  double mu_ = 1e-8, nu_ = 2.0;
};

}  // namespace triadcal

// One run's batch problem (SPEC section 6) evaluated at theta, in the two
// parts the solver needs at different rates.
//
// 1. The pass over the samples (EvaluatePass), the expensive part: for every
//    interval e -> e+1 the exact increments of block B1 at theta and their
//    Jacobian by every parameter of the layout (held ones included: the
//    consider covariance needs their columns), with the channels' noise
//    weights; for every epoch the B2 reference motion, its Jacobian and the
//    covariance the angle noise gives it. Linear in the samples; it does not
//    depend on the reading noise.
//
// 2. The reduction at a reading noise sigma_i [reading units] per channel
//    (Reduce), cheap: every residual whitened, the trajectory solved for by
//    block forward elimination (schur_covariance.h, O(E)), and what is left
//    as a function of theta alone (variable projection):
//
//      cost(theta) = min_x 0.5 sum_e |L_Q,e r_p,e|^2 + |L_R,e r_m,e|^2
//
//      r_p,e = x_{e+1} - F_e x_e - u_e(theta)      (process, B1 increments)
//      r_m,e = x_e - h_e(theta)                    (measurement, B2)
//      Q_e   = Q_iso,e + sum_i (g sigma_i / K_i)^2 W_i,e
//
//    with its gradient by theta and the Gauss-Newton information, over all
//    n parameters. The process weight follows the scale factors K_i: then
//    L_Q,e r_p,e is a fixed combination of the readings' own residuals
//    (y - W0 - K a) / sigma, so the cost is the readings' least-squares
//    cost and has no log-determinant in K (a term 0.5 log det Q_e(K) would
//    bias every scale factor by the noise's share; the expected score at
//    the truth is zero without it: docs/method.md). The Jacobian includes
//    the whitening's derivative by K_i.
//
//    The weights' shape (each channel's sensitive axis in L over the
//    interval, the angle noise through B2) is taken from a fixed reference
//    pass, the nominal values: a function of theta only through the scale
//    factors, exactly as above. Had it followed the bench angles as well, a
//    step in dpsi would rotate the quiet channel's weight onto the loud
//    one's (real roll runs: 97 / 3.2 / 70 mV) and the weights would undo
//    every step; fixed, the cost is one function of theta and its minimum one
//    point. Least squares with a fixed weight is unbiased whatever the weight;
//    the few degrees the shape may be off cost a little efficiency, which the
//    HAC covariance (and, under the model, the sigma) account for.
//
//    The reading noise is a parameter of the same likelihood: with s_i =
//    log sigma_i, -log p = cost(theta, s) + rho 0.5 sum_e log det Q_e(s),
//    the log-determinant taken at the weights' reference scale factors (the
//    readings' noise does not depend on theta), rho the share of the
//    residuals' degrees of freedom the fit leaves (restricted likelihood).
//    d/ds_i = -q_i + rho N_i, q_i = sum_e r^T Q^-1 Q_i Q^-1 r, N_i = sum_e
//    tr(Q_e^-1 Q_i,e); at fixed theta its maximum is the variance-component
//    estimate (Helmert/Foerstner) sigma_i^2 <- sigma_i^2 q_i / (rho N_i).
//    Reduce returns q_i, N_i and the log-determinant; NoiseFromReduction
//    applies the update.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/schur_covariance.h"
#include "solvers/estimation/state_space_model.h"

namespace triadcal {

// The pass over the samples at theta (all n parameters of the run's layout).
struct RunPass {
  Eigen::VectorXd theta;
  std::vector<ProcessStep> process;          // E - 1; U is 6 x n when with_jacobian
  std::vector<MeasurementStep> measurement;  // E; H is 6 x n when with_jacobian
  // With the noise (WeightsPass): each step's Q and its make-up, each epoch's
  // R and its whitening; else they are left empty.
  std::vector<Mat6> LR;  // E measurement whitenings
  bool with_jacobian = false;
  bool with_noise = false;
};

// The increments and reference motion at theta, with their Jacobian when
// asked. p must hold no parameter (p.held empty): the pass has every column.
RunPass EvaluatePass(const RunProblem& p, const Eigen::VectorXd& theta, bool with_jacobian,
                     int threads);

// The reference pass of the noise weights' shape (above), at theta_ref (the
// nominal values): the noise weights and the reference motion, no increments
// (ProcessStep::u left zero) and no Jacobian.
RunPass WeightsPass(const RunProblem& p, const Eigen::VectorXd& theta_ref, int threads);

// The run at theta with its trajectory solved for, at a reading noise.
struct RunReduction {
  double cost = 0.0;            // 0.5 chi^2 of the process and measurement residuals
  Eigen::VectorXd gradient;     // n (empty without the pass's Jacobian)
  Eigen::MatrixXd information;  // n x n, Gauss-Newton (empty without the Jacobian)
  // With the information: its diagonal before the states' elimination
  // (ThetaInformationBySchur's scale).
  Eigen::VectorXd information_scale;
  Eigen::Vector3d noise_mV = Eigen::Vector3d::Zero();  // the reading noise it was reduced at
  // Degrees of freedom of these residuals with the states solved for: 6 per
  // interval (the measurements only pin the states).
  int degrees_of_freedom = 0;
  // The noise's part of the likelihood (above): q_i and N_i per channel, the
  // log-determinant 0.5 sum_e log det Q_e (the scale factors of the weights'
  // reference: d/d log sigma_i of it is N_i), and sum_e tr((Q_e^-1 Q_i,e)^2)
  // for the estimate's effective degrees of freedom.
  Eigen::Vector3d channel_quadratic = Eigen::Vector3d::Zero();
  Eigen::Vector3d channel_trace = Eigen::Vector3d::Zero();
  Eigen::Vector3d channel_trace2 = Eigen::Vector3d::Zero();
  double log_det = 0.0;
  // sum_e (Q_i w)^T Q^-1 (Q_j w) (w = Q^-1 r) and sum_e tr(A_i A_j) (A_i =
  // Q^-1 Q_i at the weights' reference): with them the noise's Hessian,
  // d2(-log L)/ds_i ds_j = -2 q_i d_ij + 4 qq_ij + rho (2 N_i d_ij - 2 tt_ij)
  // at fixed states, less channel_state_coupling with the states solved for
  // (with the information: NoiseHessian).
  Eigen::Matrix3d channel_cross_quadratic = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d channel_cross_trace = Eigen::Matrix3d::Zero();
  // With the information and the noise's coupling (ThetaPart::
  // kGradientAndInformation): the states' response to the noise, sum p_i^T P_x
  // p_j (below), which the noise's Hessian loses when the states are solved
  // for again at each noise (zero without: the noise's Newton steps at
  // fixed theta, MaximiseNoise, take the Hessian at fixed states, on the
  // real runs within 1e-5 of it).
  Eigen::Matrix3d channel_state_coupling = Eigen::Matrix3d::Zero();
  // With the information and the noise's coupling: d gradient / d log
  // sigma_i (n x 3; empty at a fixed noise), the states
  // solved for again at each noise: the coupling of theta and the noise in
  // -log L's Hessian. With Q_i = dQ/ds_i = 2 var_i W_i it is
  // J~_theta^T (I - P_x) p_i, p_i = -L Q_i Q^-1 r per interval (L the
  // process whitening, L^T L = Q^-1; P_x the projection on the states'
  // columns): the pseudo-residual's gradient with the states eliminated.
  Eigen::MatrixXd gradient_by_log_noise;
  std::vector<Vec6> states;  // optimal (V, S) per epoch
  // Raw residuals at the optimal states: process (index e: the interval
  // ending at epoch e, zero at e = 0) and measurement (index e).
  std::vector<Vec6> process_residual, measurement_residual;
  // The whitened blocks at the optimal states (r0 = the residual there), for
  // the epoch scores (HAC) and the expected autocorrelation; with the information only.
  std::vector<ProcessBlock> process_blocks;
  std::vector<MeasurementBlock> measurement_blocks;
  // The blocks' columns (indices into theta) when the theta part was formed
  // by some of them (Reduce's columns); empty: all of them, in order.
  std::vector<int> block_columns;
};

// What a reduction forms beyond the cost, the states and the noise's part
// (all a noise estimate needs): the gradient in theta, and the information
// with the noise's coupling to theta (gradient_by_log_noise and
// channel_state_coupling: a fit that estimates the noise needs them) or
// without it (the information at a fixed noise: the decision, the score
// tests, observability).
enum class ThetaPart {
  kNone,
  kGradient,
  kGradientAndInformation,
  kGradientAndInformationAtFixedNoise
};

// weights: the WeightsPass whose noise weights' shape (each channel's
// sensitive axes in L, the angle noise through B2) whitens the residuals
// (above). The scale factors' part of the process weight is always pass's
// theta. The theta part needs the pass's Jacobian.
// columns: the theta part by these parameters only (indices into theta; the
// gradient and information are zero in the others, and the blocks hold
// these columns: block_columns), or null for all of them.
RunReduction Reduce(const RunProblem& p, const RunPass& pass, const RunPass& weights,
                    const Eigen::Vector3d& noise_mV, int threads,
                    ThetaPart theta_part = ThetaPart::kGradientAndInformation,
                    const std::vector<int>* columns = nullptr);

// The reading noise that maximises the (restricted) likelihood at the
// reduction's theta, one step of the variance-component iteration from the
// noise it was reduced at. fitted_parameters: how many parameters the fit
// estimates (rho = 1 - fitted / (6 (E - 1)), at least 0.1).
Eigen::Vector3d NoiseFromReduction(const RunReduction& r, int fitted_parameters);

// rho above: the share of the residuals' degrees of freedom the fit leaves.
double NoiseDofShare(const RunReduction& r, int fitted_parameters);

// The Hessian of -log L in s = log sigma at the reduction's theta (above).
Eigen::Matrix3d NoiseHessian(const RunReduction& r, double rho);

// Effective degrees of freedom of each channel's noise estimate
// (Satterthwaite: rho N_i^2 / sum tr(A^2)); its sd is sigma sqrt(1 / (2 dof)).
Eigen::Vector3d NoiseDegreesOfFreedom(const RunReduction& r, int fitted_parameters);

// The process covariance of step s at theta and reading noise (Q_iso + sum_i
// (g sigma_i / K_i)^2 W_i).
Mat6 ProcessCovariance(const RunProblem& p, const ProcessStep& s, const Eigen::VectorXd& theta,
                       const Eigen::Vector3d& noise_mV);

}  // namespace triadcal

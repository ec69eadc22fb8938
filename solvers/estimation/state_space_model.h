// The estimation model of a run, written once for every estimator (SPEC
// section 6, paper blocks B1 and B2). The batch solver evaluates and reduces
// them over a whole run (run_evaluation.h), the EKF predicts and updates with
// them (kalman_smoother.h), the Fisher-information analyses use the same
// reduction (observability.h), and the static method takes the prior and
// constraint rows. (GTSAM's lesson: the filter and the batch
// smoother consume the same factors.)
//
// State at epoch e: x_e = (V_e, S_e), velocity and position of O in L.
// Parameters: theta (n, SI); only the free ones (RunProblem::free) are
// estimated, the held ones stay at their nominal values and are absent from
// every Jacobian below (columns: free parameters, in RunProblem::free order).
//
// Process, interval e -> e+1 (B1 integrated over the samples between the
// epochs, inertial_increments.h):
//
//   x_{e+1} = F_e x_e + u_e(theta) + w_e,    F_e = [ I    0 ]    w_e ~ N(0, Q_e)
//                                                  [ T_e I  I ]
//   u_e = (dv_e, ds_e) = sum_j (a_j, b_j) acc_L,j   (trapezoid weights a_j, b_j)
//   Q_e = sum_i s_i^2 sum_j [ a_j^2  a_j b_j ; a_j b_j  b_j^2 ] (x) c_ij c_ij^T
//         + s_iso^2 [ sum a^2  sum ab ; sum ab  sum b^2 ] (x) I3
//
// with s_i = g sigma_i / K_i the acceleration noise of channel i (reading
// noise sigma_i [mV] through the scale factor K_i of theta, so the weight
// follows the estimate: inflating a scale factor cannot shrink the whitened
// residual), c_ij = C_L2(t_j) e_i its sensitive axis in L, and s_iso the
// angle noise rotating g. The batch solver evaluates the increments exactly
// at every theta it tries (run_evaluation.h); the filter propagates them to
// first order about its linearisation point theta_lin:
//
//   x_{e+1} = F_e x_e + u_e(theta_lin) + U_e (theta - theta_lin) + w_e
//
// Measurement, epoch e (B2 from the recorded angles alone):
//
//   0 = x_e - h_e(theta) + v_e,   h_e = (V_DU, S_DU),   v_e ~ N(0, R_e)
//   r_m = x_e - h_e(theta)
//
// R_e carries the angle noise (and the noise of lambda' estimated from the
// angles) through B2. Priors: theta ~ N(theta_0, diag(sigma_0^2)); each
// constraint c . theta = value +- sigma is one scalar row.
#pragma once

#include <array>
#include <memory>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/run_problem.h"

namespace triadcal {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// The noise of interval e -> e+1 (asked for with with_noise).
struct ProcessNoise {
  Mat6 Q = Mat6::Zero();  // covariance of w_e
  // Q's make-up, to evaluate it at another theta or noise: the isotropic
  // part and each channel's weight per unit variance (Q = Q_iso + sum_i
  // s_i^2 W_i).
  Mat6 Q_iso = Mat6::Zero();
  std::array<Mat6, 3> channel_weight;
  // The shares of the first and last sample in the noise (inertial_increments.h).
  std::array<Vec6, 3> first_channel, last_channel;
  Eigen::Vector2d first_weight = Eigen::Vector2d::Zero(), last_weight = Eigen::Vector2d::Zero();
};

// Interval e -> e+1 linearised at theta_lin.
struct ProcessStep {
  double T_s = 0.0;
  Vec6 u = Vec6::Zero();  // (dv [m/s], ds [m]) at theta_lin
  Eigen::MatrixXd U;      // 6 x n_free, du/dtheta (empty when not asked)
  // The noise, when asked (null otherwise: a pass of Jacobians at a trial
  // point holds none, 1.8 kB an interval).
  std::shared_ptr<const ProcessNoise> noise;
  Mat6 F() const;         // transition of x
};

// Epoch e evaluated at theta.
struct MeasurementStep {
  Vec6 h = Vec6::Zero();  // (V_DU [m/s], S_DU [m])
  Eigen::MatrixXd H;      // 6 x n_free, dh/dtheta (empty when not asked)
  Eigen::MatrixXd R;      // 6 x 6 covariance of v_e (empty when not asked)
};

class StateSpaceModel {
 public:
  // The problem must outlive the model.
  // The accelerometer's model does not depend on the gyro block (last in the
  // layout, gyro_term.h): it is evaluated without it, and its Jacobians get
  // zero columns there.
  explicit StateSpaceModel(const RunProblem& problem);
  // The same with the reading noise noise_mV [reading units] in place of the
  // problem's.
  StateSpaceModel(const RunProblem& problem, const Eigen::Vector3d& noise_mV);

  const RunProblem& problem() const { return p_; }
  // s_i^2 [m^2/s^4] of each channel at theta.
  Eigen::Vector3d ChannelVariance(const Eigen::VectorXd& theta) const;
  std::size_t num_epochs() const { return p_.epochs.size(); }
  int num_free() const { return static_cast<int>(p_.free.size()); }

  // theta (all n parameters) from the free ones; held ones at theta_held.
  Eigen::VectorXd Expand(const Eigen::VectorXd& theta_free) const;
  Eigen::VectorXd Free(const Eigen::VectorXd& theta) const;
  // A free-parameter covariance placed in an n x n matrix (zero rows and
  // columns for the held parameters).
  Eigen::MatrixXd ExpandCovariance(const Eigen::MatrixXd& cov_free) const;

  // Interval e -> e+1 at the full theta. with_jacobian fills U, with_noise
  // its noise, Q and its make-up (without it ProcessStep::noise is null);
  // without with_values (the noise weights' reference pass) u is left zero.
  ProcessStep Process(std::size_t e, const Eigen::VectorXd& theta, bool with_jacobian,
                      bool with_noise = true, bool with_values = true) const;
  // Epoch e at the full theta. with_jacobian fills H, with_noise R.
  MeasurementStep Measurement(std::size_t e, const Eigen::VectorXd& theta, bool with_jacobian,
                              bool with_noise) const;

  // cov(w_e, w_{e+1}) of consecutive steps at theta: the sample at their
  // common epoch ends one and starts the other (trapezoid), so their noises
  // are correlated, about +1/(4N) for V and -3/(4N) for S given V with N
  // samples an interval. The estimators treat the w_e as independent (a
  // loss of at most a few per cent of efficiency at N >= 10); the whiteness
  // tests must not (WhitenProcessSequence).
  Mat6 ProcessCrossCovariance(const ProcessStep& a, const ProcessStep& b,
                              const Eigen::VectorXd& theta) const;
  // The innovations of a sequence of process residuals r_e (of steps e = 0..,
  // consecutive) under their block-tridiagonal covariance (Q_e on the
  // diagonal, ProcessCrossCovariance beside it), each whitened: white with
  // unit variance when the model holds. Block LDL^T: S_0 = Q_0, nu_0 = r_0,
  // G_e = C_{e-1}^T S_{e-1}^-1, S_e = Q_e - G_e C_{e-1}, nu_e = r_e - G_e nu_{e-1},
  // out_e = chol(S_e)^-1 nu_e.
  std::vector<Vec6> WhitenProcessSequence(const std::vector<ProcessStep>& steps,
                                          const std::vector<Vec6>& residuals,
                                          const Eigen::VectorXd& theta) const;

  // The filter's prediction about its linearisation point, F x_a + u + U
  // dtheta_free (dtheta_free = theta - theta_lin over the free parameters).
  static Vec6 PredictLinear(const ProcessStep& s, const Vec6& xa,
                            const Eigen::VectorXd& dtheta_free);
  static Vec6 MeasurementResidual(const MeasurementStep& m, const Vec6& x) { return x - m.h; }

  // Whitened rows over the free parameters: the priors (n_free rows) and, when
  // asked, the constraints; A theta_free - b is their residual.
  void ThetaRows(bool with_constraints, Eigen::MatrixXd* A, Eigen::VectorXd* b) const;

 private:
  Eigen::MatrixXd FreeColumns(const Eigen::MatrixXd& J) const;
  // J (rows x accelerometer parameters) widened to the layout's n columns.
  Eigen::MatrixXd Widen(const Eigen::MatrixXd& J) const;
  const RunProblem& p_;
  Eigen::Vector3d noise_mV_;
  ModelConfig acc_cfg_;  // p_.cfg without the gyro block
  int n_acc_ = 0;
};

// Whitening L with L^T L = cov^-1 (L = chol(cov)^-1, lower-triangular inverse;
// its upper triangle is zero); *half_log_det, when given, 0.5 log det cov.
Mat6 WhiteningOf(const Mat6& cov, double* half_log_det = nullptr);

// The inverse of the lower triangle of L (its upper triangle is not read; the
// result's is zero): with L from Eigen's LLT (matrixLLT), chol(S)^-1, so that
// S^-1 = W^T W.
Mat6 LowerInverse(const Mat6& L);

}  // namespace triadcal

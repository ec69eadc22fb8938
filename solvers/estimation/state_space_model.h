// The estimation model of a run, written once for every estimator (SPEC
// section 6, paper blocks B1 and B2). The batch solver wraps these residuals in
// Ceres costs (batch_costs.h), the EKF predicts and updates with them
// (kalman_smoother.h), the Fisher-information analyses linearise them
// (batch_linearization.h, observability.h), and the static method takes the
// prior and constraint rows. (GTSAM's lesson: the filter and the batch
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
// angle noise rotating g. To first order about
// theta_lin (u_e sums thousands of samples, so it is evaluated once per
// linearisation, as inertial preintegration does):
//
//   r_p = x_{e+1} - F_e x_e - u_e(theta_lin) - U_e (theta - theta_lin) - c_e(theta)
//
// except for one exact part, c_e: channel i's share of u_e is proportional to
// 1 / K_i (the readings enter as (u_i - W0_i) / K_i), and a first-order
// expansion in K_i turns the noise of the readings into something a scale
// step can cancel: (u - W0) (1 - dK / K_lin) / K_lin is zero at dK = K_lin.
// On motion that hardly excites an axis (a vertical shaft: the scale factors
// ride along a flat direction) the linearised cost then falls below the noise
// as K grows and the scale factors ran to their bounds. c_e restores the
// exact 1 / K_i dependence of channel i's share u_i = -K_lin,i dU/dK_i and of
// its zero-offset term:
//
//   c_e = sum_i (f_i - 1 + dK_i / K_lin,i) u_i + (f_i - 1) U_W0i dW0_i,
//   f_i = K_lin,i / K_i
//
// (second order in dK; what stays linearised are the cross terms of K_i with
// the angles and the lever arm, which move the gravity and motion parts, not
// the noise).
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
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/run_problem.h"

namespace triadcal {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// Interval e -> e+1 linearised at theta_lin.
struct ProcessStep {
  double T_s = 0.0;
  Vec6 u = Vec6::Zero();  // (dv [m/s], ds [m]) at theta_lin
  Eigen::MatrixXd U;      // 6 x n_free, du/dtheta (empty when not asked)
  Mat6 Q = Mat6::Zero();  // covariance of w_e
  // The part of Q due to each channel's reading noise (the rest is the
  // isotropic part): the variance components of noise_estimation.h.
  std::array<Mat6, 3> channel_Q;
  // Q's make-up, to re-evaluate it at another theta: the isotropic part and
  // each channel's weight per unit variance (Q = Q_iso + sum_i s_i^2 W_i).
  Mat6 Q_iso = Mat6::Zero();
  std::array<Mat6, 3> channel_weight;
  // The exact 1 / K_i part (c_e above): free-column index of K_i and W0_i
  // (-1 when held or when U was not asked) and K_i at theta_lin.
  std::array<int, 3> scale_col{{-1, -1, -1}}, zero_col{{-1, -1, -1}};
  // The shares of the first and last sample in the noise (inertial_increments.h).
  std::array<Vec6, 3> first_channel, last_channel;
  Eigen::Vector2d first_weight = Eigen::Vector2d::Zero(), last_weight = Eigen::Vector2d::Zero();
  Eigen::Vector3d scale_lin = Eigen::Vector3d::Ones();
  Mat6 F() const;         // transition of x
};

// Epoch e evaluated at theta.
struct MeasurementStep {
  Vec6 h = Vec6::Zero();  // (V_DU [m/s], S_DU [m])
  Eigen::MatrixXd H;      // 6 x n_free, dh/dtheta (empty when not asked)
  Mat6 R = Mat6::Zero();  // covariance of v_e (zero when not asked)
};

class StateSpaceModel {
 public:
  // The problem must outlive the model.
  explicit StateSpaceModel(const RunProblem& problem) : p_(problem) {}

  const RunProblem& problem() const { return p_; }
  // s_i^2 [m^2/s^4] of each channel at theta.
  Eigen::Vector3d ChannelVariance(const Eigen::VectorXd& theta) const;
  std::size_t num_epochs() const { return p_.epochs.size(); }
  int num_free() const { return static_cast<int>(p_.free.size()); }

  // theta (all n parameters) from the free ones; held ones at theta_held.
  Eigen::VectorXd Expand(const Eigen::VectorXd& theta_free) const;
  Eigen::VectorXd Free(const Eigen::VectorXd& theta) const;

  // Interval e -> e+1 at the full theta. with_jacobian fills U.
  ProcessStep Process(std::size_t e, const Eigen::VectorXd& theta, bool with_jacobian) const;
  // Epoch e at the full theta. with_jacobian fills H, with_noise R.
  MeasurementStep Measurement(std::size_t e, const Eigen::VectorXd& theta, bool with_jacobian,
                              bool with_noise) const;

  // The whitening of the step's process residual at theta (all n), with
  // Q(theta) = Q_iso + sum_i s_i(theta)^2 W_i, and when asked its derivatives
  // by the free parameters that are scale factors (dL[j] for free index j;
  // zero for the others). Whitening with the weight of the current
  // estimate makes the whitened residual the reading-unit residual
  // (K_i r_i / (g sigma_i)): the noisy readings are then not a regressor whose
  // noise shrinks as the scale grows, which removes the errors-in-variables
  // pull on the scale factors and their runaway on motion that hardly
  // excites an axis.
  Mat6 ProcessWhitening(const ProcessStep& s, const Eigen::VectorXd& theta,
                        std::vector<Mat6>* dL_dtheta_free) const;

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

  // The process prediction x_{e+1} = F_e x_e + u_e + U_e dtheta_free for the
  // step linearised at theta_lin, dtheta_free = theta - theta_lin.
  static Vec6 Predict(const ProcessStep& s, const Vec6& xa, const Eigen::VectorXd& dtheta_free);
  // The purely linear prediction F x_a + u + U dtheta (without c_e): the
  // iterated filter's model about its linearisation point, whose RTS pass is
  // then the Gauss-Newton step of the batch problem (c_e and its derivative
  // vanish at dtheta = 0, where the two meet).
  static Vec6 PredictLinear(const ProcessStep& s, const Vec6& xa,
                            const Eigen::VectorXd& dtheta_free);
  // d Predict / d theta_free at dtheta_free: U_e plus the derivative of c_e
  // (U_e itself at dtheta_free = 0).
  static Eigen::MatrixXd PredictThetaJacobian(const ProcessStep& s,
                                              const Eigen::VectorXd& dtheta_free);
  // r_p = x_{e+1} - Predict(x_e).
  static Vec6 ProcessResidual(const ProcessStep& s, const Vec6& xa, const Vec6& xb,
                              const Eigen::VectorXd& dtheta_free);
  // d r_p / d x_a = -F_e, d r_p / d x_b = I, d r_p / d theta = -PredictThetaJacobian.
  static Mat6 ProcessJacobianXa(const ProcessStep& s) { return -s.F(); }
  static Vec6 MeasurementResidual(const MeasurementStep& m, const Vec6& x) { return x - m.h; }

  // Whitened rows over the free parameters: the priors (n_free rows) and, when
  // asked, the constraints; A theta_free - b is their residual.
  void ThetaRows(bool with_constraints, Eigen::MatrixXd* A, Eigen::VectorXd* b) const;

 private:
  Eigen::MatrixXd FreeColumns(const Eigen::MatrixXd& J) const;
  const RunProblem& p_;
};

// Whitening L with L^T L = cov^-1 (L = chol(cov)^-1, lower-triangular inverse).
Mat6 WhiteningOf(const Mat6& cov);

}  // namespace triadcal

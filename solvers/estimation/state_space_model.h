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
//   u_e = (dv_e, ds_e),   Q_e = s^2 [ sum a^2  sum ab ; sum ab  sum b^2 ] (x) I3
//
// with s^2 the variance of one acceleration sample. To first order about
// theta_lin (u_e sums thousands of samples, so it is evaluated once per
// linearisation, as inertial preintegration does):
//
//   r_p = x_{e+1} - F_e x_e - u_e(theta_lin) - U_e (theta - theta_lin)
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

  // r_p for the step linearised at theta_lin, dtheta_free = theta - theta_lin
  // over the free parameters.
  static Vec6 ProcessResidual(const ProcessStep& s, const Vec6& xa, const Vec6& xb,
                              const Eigen::VectorXd& dtheta_free);
  // d r_p / d x_a = -F_e, d r_p / d x_b = I, d r_p / d theta = -U_e.
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

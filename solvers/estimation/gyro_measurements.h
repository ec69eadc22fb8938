// The gyro's increment residuals (gyro_term.h) as the filter's measurements
// of theta: the same residual, Jacobian and noise the batch fit minimises,
// taken one interval at a time.
//
// The residual r_k(theta) of interval k involves theta alone (the gyro's 21
// parameters, dlambda2, the angle stage and, through the specific force of
// the g-sensitivity, the accelerometer's readings model): no velocity or
// position. Consecutive residuals share an epoch's angle noise and the
// trapezoid's sample, so their covariance is block tridiagonal (C_kk on the
// diagonal, C_k,k+1 beside it); its block LDL^T turns them into innovations
// that are independent, with the same likelihood (gyro_term.h):
//
//   S_0 = C_00,  nu_0 = r_0
//   G_k = C_k-1,k^T S_k-1^-1,  S_k = C_kk - G_k C_k-1,k,  nu_k = r_k - G_k nu_k-1
//
// Each nu_k is linear in the r_j, j <= k, so as a function of theta it has
// the Jacobian Jnu_k = J_k - G_k Jnu_k-1. The filter takes
//
//   0 = nu_k(theta) + v_k,  v_k ~ N(0, S_k)
//
// as an EKF measurement of the parameter states, linearised at its current
// estimate theta_l:  nu_k(theta) = nu_k(theta_l) + Jnu_k (theta - theta_l),
// with the scale factors' and misalignments' columns of J_k in the readings'
// form (GyroPass::J_info, the fit's information). The residual is in input-
// rate units and its noise, sigma_i / K_i along P Mg^-1 e_i, follows them:
// the fit's cost sum |L(theta)^-1 nu(theta)|^2 (L L^T = S) has its weights'
// derivatives in the gradient. With one channel, r = y / K - w, S = s^2 /
// K^2: the inverse model's column -y / K^2 at fixed weights regresses w on
// the noisy y (K biased up by s^2 / (K w)^2: 0.9 % on the real roll run's
// 8 deg/s of drive vibration), while the readings' form -w / K whitened by
// K / s is the derivative of (y - K w) / s, the fit's gradient and
// information at once. The rest of J_k is the inverse model's (the
// offsets, g-sensitivities, dlambda2 and the angle stage enter it linearly
// in y's place),
// with nu_k-1(theta_l) carried from where it was linearised to first order
// (nu_k-1(theta_l) = nu_k-1(theta_k-1) + Jnu_k-1 (theta_l - theta_k-1)). The
// covariance blocks are taken at theta_l's scale factors and misalignments
// and at the filter's reading noise (declared, or the readings' own with
// noise_dps: auto). An interval holding a clipped gyro sample is left out
// and the chain starts again after it (the intervals either side share no
// epoch), as in the fit.
#pragma once

#include <cstddef>
#include <memory>

#include <Eigen/Core>

#include "solvers/estimation/gyro_term.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// Interval k as an independent measurement of theta.
struct GyroInnovation {
  Eigen::Vector3d nu = Eigen::Vector3d::Zero();  // nu_k at theta_l [rad]
  Eigen::MatrixXd H;                             // 3 x n, d nu_k / d theta (all parameters)
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();   // its covariance [rad^2]
};

class GyroMeasurements {
 public:
  // The problem must outlive this; noise_rad_s is each channel's reading
  // noise (gyro_term.h's unit). Requires RunHasGyro(p).
  GyroMeasurements(const RunProblem& p, const Eigen::Vector3d& noise_rad_s);

  std::size_t size() const { return intervals_; }
  // The sample that ends interval k (its measurement is known there).
  std::size_t end_sample(std::size_t k) const { return p_.gyro_epochs[k + 1]; }

  // Starts a pass (the chain from interval 0). With theta_lin, every
  // interval of the pass is linearised there (evaluated at once, on
  // `threads`); without, each at the theta given to Next.
  void Start(const Eigen::VectorXd* theta_lin, int threads = 1);
  // Interval k (k = 0, 1, ... in order) at theta (the full n-vector; ignored
  // when the pass has theta_lin). False when the interval is left out
  // (clipped): no measurement.
  bool Next(std::size_t k, const Eigen::VectorXd& theta, GyroInnovation* out);

 private:
  const RunProblem& p_;
  Eigen::Vector3d noise_rad_s_;
  std::size_t intervals_ = 0;
  std::unique_ptr<GyroPass> fixed_;  // the pass at theta_lin, when given
  // The chain: the previous interval's innovation, its Jacobian and where it
  // was linearised, and its covariance with this one.
  bool chained_ = false;
  Eigen::Vector3d nu_prev_;
  Eigen::MatrixXd H_prev_;
  Eigen::VectorXd theta_prev_;
  Eigen::Matrix3d S_prev_, C_prev_;
};

}  // namespace triadcal

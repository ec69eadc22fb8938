#include "solvers/estimation/gyro_measurements.h"

#include <Eigen/Cholesky>
#include <stdexcept>

namespace triadcal {

GyroMeasurements::GyroMeasurements(const RunProblem& p, const Eigen::Vector3d& noise_rad_s)
    : p_(p), noise_rad_s_(noise_rad_s) {
  if (!RunHasGyro(p)) throw std::logic_error("GyroMeasurements: the run has no gyro");
  intervals_ = p.gyro_epochs.size() - 1;
}

void GyroMeasurements::Start(const Eigen::VectorXd* theta_lin, int threads) {
  chained_ = false;
  fixed_.reset();
  if (theta_lin) {
    fixed_ = std::make_unique<GyroPass>(EvaluateGyroPass(p_, *theta_lin, true, threads));
  }
}

bool GyroMeasurements::Next(std::size_t k, const Eigen::VectorXd& theta, GyroInnovation* out) {
  GyroPass one;
  const GyroPass* pass = fixed_.get();
  std::size_t i = k;
  if (!pass) {
    one = EvaluateGyroPass(p_, theta, true, 1, k, 1);
    pass = &one;
    i = 0;
  }
  if (!pass->valid[i]) {
    chained_ = false;
    return false;
  }
  Eigen::Matrix3d C, C_next;
  GyroIncrementCovariance(*pass, i, noise_rad_s_, &C, &C_next);
  out->nu = pass->r[i];
  // The scale factors' and angles' columns in the readings' form (as the
  // fit's information): with the noise's weights following them, they make
  // the update the Gauss-Newton step of the fit's cost (above).
  out->H = pass->J[i];
  const int go = p_.cfg.layout.gyro_offset();
  for (int q = 0; q < 3; ++q) out->H.col(go + kGKx + q) = pass->J_info[i].col(q);
  for (int q = 0; q < 6; ++q) out->H.col(go + kGAlphaX + q) = pass->J_info[i].col(3 + q);
  out->S = C;
  if (chained_) {
    // nu_k-1 carried to this interval's linearisation point.
    const Eigen::Vector3d nu_prev = nu_prev_ + H_prev_ * (pass->theta - theta_prev_);
    const Eigen::Matrix3d G = S_prev_.llt().solve(C_prev_).transpose();  // C^T S^-1
    out->S -= G * C_prev_;
    out->nu -= G * nu_prev;
    out->H -= G * H_prev_;
  }
  out->S = 0.5 * (out->S + out->S.transpose());
  nu_prev_ = out->nu;
  H_prev_ = out->H;
  theta_prev_ = pass->theta;
  S_prev_ = out->S;
  C_prev_ = C_next;
  chained_ = true;
  return true;
}

}  // namespace triadcal

// What a fit reports about its reading noise, and the whiteness test of its
// residuals. The noise itself is a parameter of the likelihood, estimated
// per channel with theta (run_evaluation.h, batch_minimizer.h): its
// variance-component maximum (Helmert/Foerstner; Koch, Parameter Estimation
// and Hypothesis Testing in Linear Models, sec. 3.6), restricted likelihood
// (the fit's own share of the residuals' degrees of freedom taken off).
// The estimate's sampling error follows from its effective degrees of
// freedom (Satterthwaite): nu_i = (sum_e tr A_e)^2 / sum_e tr(A_e^2), A_e =
// Q_e^-1 Q_i,e; sd(sigma_i) = sigma_i sqrt(1 / (2 nu_i)).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/state_space_model.h"

namespace triadcal {

struct NoiseEstimate {
  Eigen::Vector3d assumed_mV = Eigen::Vector3d::Zero();    // declared in run.yaml
  Eigen::Vector3d estimated_mV = Eigen::Vector3d::Zero();  // with the parameters
  Eigen::Vector3d sd_mV = Eigen::Vector3d::Zero();         // sampling error of the estimate
  Eigen::Vector3d dof = Eigen::Vector3d::Zero();           // effective degrees of freedom
  // |estimated - declared| within 3 sd in every channel (or within 2 %).
  bool consistent = true;
  // Lag-1 autocorrelation of each whitened process residual component (V
  // then S), and whether all are within white_bound: max(kWhiteLag1,
  // 4/sqrt(E)), the fit's own -p/E and the sampling error 1/sqrt(E) on short
  // runs.
  Eigen::Matrix<double, 6, 1> lag1 = Eigen::Matrix<double, 6, 1>::Zero();
  bool white = true;
  double white_bound = 0.0;
};

// |lag-1| of the whitened residual beyond which it is not called white.
constexpr double kWhiteLag1 = 0.3;

// The fewest effective degrees of freedom per channel that an estimated noise
// needs (sd of sigma <= 13 %).
constexpr double kMinNoiseDof = 30.0;

// Whiteness of the whitened process residual (index 0, the first epoch, ends
// no interval): Ljung-Box per component over lags min(20, E/5) with the
// autocorrelation the fit leaves subtracted (expected_acf, lags 1..; may be
// empty), Bonferroni over the 6 components; white when p >= 0.01.
struct WhitenessSummary {
  double p_value = 1.0;
  bool white = true;
};
WhitenessSummary ProcessWhiteness(const std::vector<Vec6>& process_whitened,
                                  const std::array<std::vector<double>, 6>& expected_acf);

// The autocorrelation at lags 1..lags that the whitened process residuals
// (6 channels) have at a least-squares solution even when the model holds:
// r = (I - H) w with H(t, u) = j_t^T cov j_u, j_t the whitened residual's
// derivative by the free parameters (C[t], 6 x n_free) and cov their
// covariance; rho_k = -sum_t H(t, t+k) / sum_t (1 - H(t, t)). Smooth
// regressors make it negative at short lags, about -(parameters a channel
// carries) / (epochs); the whiteness tests subtract it. The channels on
// `threads`.
std::array<std::vector<double>, 6> ExpectedProcessAutocorrelation(
    const std::vector<Eigen::MatrixXd>& C, const Eigen::MatrixXd& cov_free, int lags,
    int threads = 1);

}  // namespace triadcal

// A covariance of theta that stays honest when the residuals are correlated in
// time: the sandwich I^-1 B I^-1 with B a heteroscedasticity-and-
// autocorrelation-consistent (HAC) estimate of the scores' long-run
// covariance (Newey and West 1987; bandwidth by Andrews 1991).
//
// Why the epoch scores. The batch problem has a trajectory state at every
// epoch, so its residuals are not independent pieces of data: a residual's
// per-block gradient J_theta^T r shares the states with its neighbours, and a
// sandwich over those blocks came out at 0.28-1.0 of the white sigma on a clean
// run, where it must be 1. The scores of schur_covariance.h's EpochScores are
// the gradient of what each epoch adds given the epochs before it (the
// prediction-error decomposition): under the model they are uncorrelated
// between epochs with covariance the information each epoch adds, so
//
//   B = sum_e s_e s_e^T + sum_{l=1..L} w_l sum_e (s_e s_{e-l}^T + s_{e-l} s_e^T)
//
// (Bartlett weights w_l = 1 - l / S) estimates the data's information when the
// residuals are white and the long-run covariance of the scores when they are
// not. The priors' and constraints' rows are independent of the data: their
// information enters B as it is. B scales with the residuals, so a declared
// noise that is wrong by a factor is corrected as well.
//
// Prewhitening (Andrews and Monahan 1992; off by default), per parameter: an
// AR(1) filter u_e = s_e - rho_a s_{e-1}, the kernel estimate on u,
// recoloured by 1 / (1 - rho_a). Measured both ways: on simulated runs with
// Gauss-Markov reading noise (bench/honesty.py --only coloured, 181 epochs)
// RMS z is 1.16 without and 0.91 with it (1.04 without at 721 epochs); on the
// real medium roll run cut in halves (--only real) the halves agree at a
// median chi2/dof of 0.92 without and 0.29 with it: there the scores' lag-1
// reaches 0.9 and the recolouring
// 1 / (1 - rho)^2 (up to 1100 at the 0.97 cap) inflates sigma up to 15x. The
// plain estimate is the default.
//
// The bandwidth S: Andrews's AR(1) plug-in for the Bartlett kernel,
// S = 1.1447 (alpha N)^(1/3), alpha from an AR(1) fit to each parameter's
// score series (those the data determine), so white scores give S of 1-3
// epochs and strongly correlated ones tens of epochs.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace triadcal {

struct HacCovariance {
  Eigen::MatrixXd cov;       // I^-1 B I^-1 (n x n)
  double bandwidth = 0.0;    // S, in epochs (lags l < S carry weight)
  double score_lag1 = 0.0;   // largest |lag-1 autocorrelation| of a parameter's scores
};

// scores: E per-epoch score vectors (n each); information: the Fisher
// information of theta with the priors (and constraints) included;
// theta_rows_information: that of the priors and constraints alone (A^T A).
// bandwidth < 0 chooses S from the data; 0 gives the plain sandwich (no lags).
// A small-sample factor N / (N - k) on the data part (N = 6 (E - 1) innovation
// components, k the parameters the data determine) makes up for the fit's own
// shrinkage of the residuals.
HacCovariance HacThetaCovariance(const std::vector<Eigen::VectorXd>& scores,
                                 const Eigen::MatrixXd& information,
                                 const Eigen::MatrixXd& theta_rows_information,
                                 double bandwidth = -1.0, bool prewhiten = false);

// Andrews's AR(1) plug-in bandwidth for the Bartlett kernel over the given
// series (one per column of `series`, E rows; columns with weight 0 ignored).
double BartlettBandwidth(const Eigen::MatrixXd& series, const Eigen::VectorXd& weight,
                         double* largest_lag1 = nullptr);

// cov with each variance raised to at least floor's (rows and columns scaled
// by max(1, sqrt(floor_ii / cov_ii)): the correlations stay, the matrix stays
// positive semi-definite). The HAC estimate is noisy and, with a finite
// bandwidth, biased low under strong correlation; the reported sigma is never
// below the model's.
Eigen::MatrixXd FloorVariances(const Eigen::MatrixXd& cov, const Eigen::MatrixXd& floor);

}  // namespace triadcal

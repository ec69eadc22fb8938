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
// recoloured by 1 / (1 - rho_a). Measured both ways, before the kernel-bias
// correction below: on simulated runs with Gauss-Markov reading noise
// (bench/honesty.py --only coloured, 181 epochs) RMS z was 1.16 without and
// 0.91 with it (1.04 without at 721 epochs); on the real medium roll run cut
// in halves (--only real) the halves agreed at a median chi2/dof of 0.92
// without and 0.29 with it: there the scores' lag-1 reaches 0.9 and the
// recolouring 1 / (1 - rho)^2 (up to 1100 at the 0.97 cap) inflates sigma up
// to 15x. The plain estimate is the default.
//
// The kernel's bias, corrected (on by default). At bandwidth S the Bartlett
// weights take, of an AR(1) series with lag-1 rho and variance g0, not its
// long-run variance g0 (1 + rho) / (1 - rho) but
//   g0 (1 + 2 sum_{1 <= l < S} (1 - l / S) rho^l),
// low by about 2 rho / ((1 - rho^2) S) of the former (rho 0.4 at S 7.5: 13 %
// of the variance). On the 181 epochs of a 90-s run that bias, not the
// estimate's spread, was most of the RMS z of 1.16 above. So each
// parameter's row and column of the data's part of the covariance,
// I^-1 B I^-1, is scaled by the square root of the ratio of the two at the
// lag-1 of its influence series I^-1 s_e (what each epoch adds to its error;
// kernel_bias_factor): the correlations stay, the matrix stays positive
// semi-definite. Not at the raw scores' lag-1: where the information
// correlates parameters, their scores mix (s = I v), and a factor on B from
// a mixture spoils the cancellation in I^-1 B I^-1 (the slow real roll run's
// first fit, before the loop: sigma of Kx 2.47 -> 37 mV/g that way, 2.47
// as before this way; test KernelBiasCorrectionFollowsEachParametersInfluence).
// Unlike prewhitening, only the part the kernel misses is extrapolated from
// the AR(1) fit, so the factor stays moderate where the lag-1 is large (0.9
// at S = 20: 1.31 on sigma; prewhitening's recolouring there is 10; on the
// real medium and fast roll runs the largest factor is 1.05). Measured (docs/method.md,
// docs/validation.md): on 400 AR(1) series of 181 epochs with rho 0.4 the
// mean estimate goes from 0.85 to 1.00 of the long-run variance (test
// KernelBiasCorrectionRestoresTheLongRunVarianceOnFewEpochs); on the coloured
// paper runs RMS z 1.16 -> 1.08 at 90 s (20 seeds; 100 seeds: 1.077, factor
// 1.10-1.18) and 0.98 at 360 s; on white runs the factor's spread is a few
// per cent and the floor at the model's covariance keeps sigma where it was.
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
  // Per parameter, the kernel-bias correction's factor on sigma (1 without it).
  Eigen::VectorXd kernel_bias_factor;
};

// One run's part of the data's covariance, I^-1 B I^-1 with B the run's
// kernel estimate over its own epochs (lags never cross into another run), the
// small-sample factor N / (N - k) (N = 6 (E - 1) innovation components, k =
// the weights' sum) and, when asked, the kernel-bias factors. information_inverse:
// I^-1 of the whole problem (one run, or several fitted together); weight: 1
// for the parameters this run's data determine (they choose the bandwidth and
// count in k), 0 for the others. The joint fit of several runs sums these
// parts, one per run whose residuals are not white (joint_solver.h).
struct HacDataPart {
  Eigen::MatrixXd cov;
  double bandwidth = 0.0;
  double score_lag1 = 0.0;
  Eigen::VectorXd kernel_bias_factor;
};
HacDataPart HacDataCovariance(const std::vector<Eigen::VectorXd>& scores,
                              const Eigen::MatrixXd& information_inverse,
                              const Eigen::VectorXd& weight, double bandwidth = -1.0,
                              bool prewhiten = false, bool correct_kernel_bias = true);

// The whole sandwich of one run: its data part above plus the priors' and
// constraints' information as it is.
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
                                 double bandwidth = -1.0, bool prewhiten = false,
                                 bool correct_kernel_bias = true);

// The lag-1 autocorrelation of a series (mean removed, least squares).
double Lag1(const Eigen::VectorXd& series);

// The long-run variance of an AR(1) series with lag-1 rho (clamped to
// +-0.97) over its Bartlett estimate's expectation at the given bandwidth,
// lags up to max_lag (>= 1 for rho > 0).
double BartlettAr1Ratio(double rho, double bandwidth, Eigen::Index max_lag);

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

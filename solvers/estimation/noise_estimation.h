// The reading noise from the run itself: variance components of the process
// residuals (Helmert / Foerstner; Koch, Parameter Estimation and Hypothesis
// Testing in Linear Models, sec. 3.6).
//
// The process covariance of every interval is a sum of components
// (state_space_model.h), Q_e = sum_i s_i^2 W_i,e + Q_iso,e, one per channel
// i = x, y, z. After a fit with residuals r_e, channel i's variance factor is
//
//   f_i = sum_e r_e^T Q_e^-1 Q_i,e Q_e^-1 r_e  /  ( rho sum_e tr(Q_e^-1 Q_i,e) )
//
// and the new noise is sigma_i sqrt(f_i). rho = dof / (6 (E - 1)) is the
// share of the process residuals' degrees of freedom left after the fit (the
// trajectory is pinned by the precise B2 measurements, so the process
// residuals carry the redundancy, less the free parameters); the exact
// redundancy matrix is replaced by rho I. The estimate's sampling error
// follows from its effective degrees of freedom (Satterthwaite)
//
//   nu_i = ( sum_e tr(A_e) )^2 / sum_e tr(A_e^2),   A_e = Q_e^-1 Q_i,e,
//
// sd(f_i) = f_i sqrt(2 / nu_i), sd(sigma_i) = sigma_i sqrt(1 / (2 nu_i)).
//
// These components are the noise only when the residual is noise. When the
// model lacks an effect (an angle latency on a real run), the residual is
// mostly that effect's smooth mark, and it falls unequally on the channels:
// on the real medium roll run the declared model's residual made x and z
// "noise" 98 and 69 mV against 3.4 mV in y. Weighting the channels by those
// figures hands the fit to the y channel (1000x the weight of the others),
// drives y's parameters beyond their priors and stops the solver converging.
// So the per-channel split is used only when the channels are alike (below)
// and the whitened residual is white enough to be noise (lag-1 autocorrelation
// within kWhiteLag1 of zero in every component, or 4/sqrt(E) on short runs,
// where the fit's own -p/E and the sampling error 1/sqrt(E) are larger);
// otherwise the batch solver keeps the declared weights and scales the
// covariance by one a-posteriori variance factor, chi2/dof (batch_solver.h):
// the misfit is then spread over the channels and the angles as the declared
// noise spreads it, and sigma carry it.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/batch_linearization.h"
#include "solvers/estimation/state_space_model.h"

namespace triadcal {

struct NoiseEstimate {
  Eigen::Vector3d assumed_mV = Eigen::Vector3d::Zero();    // what the fit used
  Eigen::Vector3d estimated_mV = Eigen::Vector3d::Zero();  // from its residuals
  Eigen::Vector3d sd_mV = Eigen::Vector3d::Zero();         // sampling error of the estimate
  Eigen::Vector3d dof = Eigen::Vector3d::Zero();           // effective degrees of freedom
  // |estimated - assumed| within 3 sd in every channel (or within 2 %); the
  // batch solver replaces it by the variance factor's test when the split is
  // not used.
  bool consistent = true;
  // Lag-1 autocorrelation of each whitened process residual component (V
  // then S), and whether all are within the white bound (see above).
  Eigen::Matrix<double, 6, 1> lag1 = Eigen::Matrix<double, 6, 1>::Zero();
  bool white = true;
  double white_bound = 0.0;
  // The per-channel figures are within kMaxChannelRatio of each other.
  bool channels_alike = true;
  // Whether the per-channel split is used: white and alike.
  bool PerChannel() const { return white && channels_alike; }
};

// The channels of one triad share their noise density to within a small
// factor; a larger spread in the residual is signal-dependent error (time-stamp
// jitter acts only on the channels whose reading changes) or misfit. On the
// real medium roll run with its latency and drift fitted the residual is
// nearly white (worst lag-1 0.23) yet splits 20.5 / 3.1 / 16.7 mV: the shaft
// channel, which reads a constant, quantised 0.01 g, weighted 40x the others,
// went on to 1.5 mV (below its quantisation, 2.9 mV) and W0y to 238 mg.
constexpr double kMaxChannelRatio = 3.0;

// |lag-1| of the whitened residual beyond which it is not taken for noise.
constexpr double kWhiteLag1 = 0.3;

// From the raw process residuals (index e: the interval ending at epoch e,
// e >= 1) of a fit linearised at lin, with dof the fit's degrees of freedom,
// and the same residuals whitened as a sequence (for the whiteness; may be
// empty: then taken as white).
NoiseEstimate EstimateChannelNoise(const StateSpaceModel& model, const BatchLinearization& lin,
                                   const std::vector<Vec6>& process_residual, int dof,
                                   const std::vector<Vec6>& process_whitened);

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

}  // namespace triadcal

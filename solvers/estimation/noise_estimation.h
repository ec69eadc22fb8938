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
#pragma once

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
  // |estimated - assumed| within 3 sd in every channel (or within 2 %).
  bool consistent = true;
};

// From the raw process residuals (index e: the interval ending at epoch e,
// e >= 1) of a fit linearised at lin, with dof the fit's degrees of freedom.
NoiseEstimate EstimateChannelNoise(const StateSpaceModel& model, const BatchLinearization& lin,
                                   const std::vector<Vec6>& process_residual, int dof);

// The fewest effective degrees of freedom per channel that an estimated noise
// needs (sd of sigma <= 13 %).
constexpr double kMinNoiseDof = 30.0;

}  // namespace triadcal

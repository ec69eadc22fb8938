// The paper's filter (blocks B1, B2 and the optimal filter of Fig. 2) as an
// extended Kalman filter with a fixed-interval Rauch-Tung-Striebel smoother.
//
// State (paper eq. 5, in total-state form): x = [V_L (3), S_L (3), theta (n)],
// V and S the velocity and position of O in L, theta every parameter of the
// layout (27 base parameters, plus effects). Between epochs (every epoch_s) the
// process model is B1 integrated over the accelerometer samples
// (inertial_increments.h):
//
//   V_b = V_a + dv(theta),  S_b = S_a + V_a T + ds(theta),  theta_b = theta_a
//
// with process noise from the accelerometer white noise (and the angle noise
// that rotates g). At each epoch the filter observes (block B2)
//
//   z_V = V - V_DU(lambda, lambda', theta) = 0,   z_S = S - S_DU(lambda, theta) = 0
//
// with measurement noise from the angle-sensor noise (and the noise of lambda'
// estimated from the recorded angles, angle_derivatives.h). Every constraint of
// run.yaml is one scalar pseudo-measurement at the first epoch (it is one piece
// of information, not one per epoch). The extended filter relinearises B1 and B2
// about its current estimate at each epoch.
//
// Gyro (when the layout has the gyro block and the data its columns,
// gyro_measurements.h): each of the gyro's increment residuals (gyro_term.h,
// the batch fit's residual, every kGyroEpoch_s) is a measurement of theta
// alone, 0 = nu_k(theta) + v_k with the innovations of their block LDL^T (so
// that they are independent), applied at the first epoch at or after the
// interval's end; the gyro's parameters are constants like the others. Its
// noise is the run's gyro.noise_dps (with auto, the readings' own: the
// caller's, sample_noise.h WithReadingNoise), at least kGyroNoiseFloor_dps.
//
// Smoother: for constant parameters the RTS smoother's theta (at any epoch)
// equals the final filtered theta of the same linearisation, so that is what
// it returns; the backward recursion would only improve the trajectory,
// which nothing reads. With smoother_iterations > 1 the whole pass is
// repeated linearised about the previous smoothed estimate (iterated extended
// Kalman smoother, i.e. Gauss-Newton on the batch problem), which removes the
// linearisation error of the early epochs.
//
// Cost: O(N^3) an epoch for the N = 6 + n states (the covariance's
// propagation and the Joseph update are dense products: kalman_smoother.cpp
// says why). Memory: the current state and covariance.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/angle_derivatives.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "core/model/priors.h"
#include "solvers/estimation/gyro_term.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// The least gyro reading noise the filter runs at [deg/s per channel]: with
// noise-free readings and angles the increments' covariance is singular
// (a MEMS gyro's white noise is 0.005 deg/s or more).
constexpr double kGyroNoiseFloor_dps = 1e-4;

struct FilterOptions {
  double epoch_s = kDefaultEpoch_s;  // measurement epochs
  // Held at their nominal values: absent from the filter's state.
  std::vector<std::string> held;
  AngleDerivativeOptions derivatives;
  int smoother_iterations = 2;
  // The gyro's increments as measurements when the run has a gyro (the
  // layout's gyro block and the data's columns). Off: the gyro's readings are
  // not used (its parameters must then be held, or they stay at the prior).
  bool gyro = true;
  int threads = 0;  // the angles' derivatives and the gyro's whole-run passes (0: all cores)
  bool keep_series = false;
  // Called with (pass, fraction done) now and then; may be empty.
  std::function<void(int, double)> progress;
};

struct Estimate {
  Eigen::VectorXd theta;  // SI
  Eigen::MatrixXd cov;    // SI, n x n
};

// One row of the forward pass (the paper's Figs. 4-5) and its innovations.
struct FilterSeriesRow {
  double t_s;
  Eigen::VectorXd theta, sigma;            // SI
  Eigen::Matrix<double, 6, 1> innovation;  // V [m/s] then S [m]
  Eigen::Matrix<double, 6, 1> innovation_sigma;
};

struct FilterResult {
  Estimate ekf;  // end of the first forward pass
  Estimate rts;  // smoothed (the last pass's last filtered theta: constants)
  // The time of the first epoch at which the covariance lost its positive
  // definiteness (a negative variance, or not finite): the filter diverged
  // there and its estimates are no result. -1 when it never did.
  double diverged_at_s = -1.0;
  Prior prior;
  std::vector<FilterSeriesRow> series;  // first forward pass, when asked
  int epochs = 0;
  int passes = 0;
  double rate_noise_rad_s = 0.0;  // noise assumed on lambda'
  // Innovation statistics of the last forward pass.
  Eigen::Matrix<double, 6, 1> innovation_rms = Eigen::Matrix<double, 6, 1>::Zero();
  double mean_nis = 0.0;  // E = 6 for a consistent filter
  // The gyro, when the filter took its increments (gyro.present): at the
  // smoothed estimate, the residuals and their whitening at the noise the
  // filter ran at (gyro.noise_rad_s; whitened RMS 1 when that noise is
  // right), and the noise at the maximum likelihood there (a check of it,
  // as fit estimates it). gyro_mean_nis: the last forward pass's mean
  // normalised innovation squared of the gyro's measurements (E = 3).
  GyroSummary gyro;
  Eigen::Vector3d gyro_noise_ml_rad_s = Eigen::Vector3d::Zero();
  double gyro_mean_nis = 0.0;
  int gyro_measurements = 0;  // per forward pass
};

FilterResult RunFilterSmoother(const RunDescription& run, const RunData& data,
                               const ParameterLayout& layout, const FilterOptions& options);

}  // namespace triadcal

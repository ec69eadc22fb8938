// The gyro triad's part of the batch problem (SPEC section 10): what the gyro
// adds to a run's negative log-likelihood, as a function of theta alone.
//
// Residual. The angle sensors give the bench's attitude, the gyro its rate. As
// the paper integrates the accelerometers against the angles (velocity and
// position, never lambda''), the gyro is integrated against them, never
// against lambda' (differentiating angles with 15'' noise at 100 Hz gives a
// rate noise of ~0.6 deg/s, ten times a MEMS gyro's). Frame 2's rate turned
// into the outer-axis frame is exactly the bench's angle rates,
//
//   Rx(l2 + dlambda2) w_2 = (l2', l1', 0)            (gyro_model.h)
//
// so with the gyro's rate w^_j = GyroRateFromReadings at each sample j, the
// increment residual of interval e (epochs e -> e+1, trapezoid weights a_j)
//
//   r_e = sum_j a_j Rx(l2_j + dlambda2) (w^_j - C_L2,j^T Omega_L)
//         - (l2_{e+1} - l2_e, l1_{e+1} - l1_e, 0)
//
// is zero but for noise: each gyro channel's white noise integrated, and the
// angle noise at the two epochs (15'' on each, the same size as 0.05 deg/s
// integrated over 0.5 s at 100 Hz). Consecutive residuals share an epoch's
// angle noise (and the trapezoid's shared sample): their covariance is block
// tridiagonal, and the innovations of its block LDL^T whiten them exactly, in
// O(E) (the same likelihood as keeping the attitude as a state and solving
// for it; no state is needed since the residual is linear in it):
//
//   S_0 = C_00, nu_0 = r_0;  G_e = C_{e-1,e}^T S_{e-1}^-1,
//   S_e = C_ee - G_e C_{e-1,e},  nu_e = r_e - G_e nu_{e-1}
//   -log L = 0.5 sum nu^T S^-1 nu + rho 0.5 sum log det S_e
//
// Noise. Each channel's reading noise sigma_i is a parameter of the same
// likelihood, held at its (restricted) maximum at every theta (Newton on -log L
// in log sigma; rho = 1 - fitted / (3 (E - 1)), as the accelerometer's): the
// minimiser works on the likelihood profiled over it. In the residual, which
// is in input-rate units, channel i's noise is sigma_i / K_i along P Mg^-1
// e_i: the weights follow the scale factors and the misalignment, so that
// inflating K_i cannot shrink the whitened residual (a channel that never
// sees a rate would otherwise be silenced by K_i -> infinity), and a quiet
// channel is not charged with a loud one's noise (a misalignment of 46'
// carries 1.4 % of the shaft channel's into another). The log-determinant is
// taken at the reference values (the readings' noise does not depend on
// theta), as the accelerometer's (run_evaluation.h). The gradient carries the
// weights' derivatives, -0.5 w^T dSigma w with w = Sigma^-1 r (the block
// factorisation's back substitution): by K_i through sigma_i / K_i, by the
// angles through P Mg^-1 e_i (ReduceGyroAtNoise). The
// Gauss-Newton information takes K_i's and the angles' columns in the
// readings' form, -P Mg^-1 dM (Mg w) with w the bench's rate from the angles
// (differenced over +-0.05 s), which the weights' derivatives make of the
// inverse model's columns (those carry the readings' noise). The angle noise
// is the run's declared one. The rotation in the noise's weights uses the
// recorded inner angle (dlambda2 turns it by arcminutes).
//
// Jacobian (written out; GyroRateFromReadings is linear in the readings):
// by the gyro's 21 parameters, dlambda2, the angle stage's parameters and,
// through the specific force W of the g-sensitivity (the accelerometer's
// readings model inverted at theta), the accelerometer's sensor-stage
// parameters (Jets through SpecificForceFromReadings_g). Earth's rate enters
// with its value only (7e-5 rad/s times angles of arcminutes).
//
// Saturation: an interval holding a gyro sample at the range's limit
// (RunData::gyro_clipped, found by the reader) is left out; the intervals on
// either side of a gap share no epoch and are independent.
//
// The angle stage (latency, encoder harmonic, angle scale) is undone at every
// sample as for the accelerometer's residuals (bench_model.h
// BenchAnglesFromRecorded), with its derivatives: angle_latency is then the one
// time offset between the angle sensors and both triads.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/run_problem.h"

namespace triadcal {

// True when the run's layout has the gyro block and its data the gyro columns.
bool RunHasGyro(const RunProblem& p);

// The pass over the samples at theta (all n parameters of the run's layout).
struct GyroPass {
  Eigen::VectorXd theta;
  std::vector<Eigen::Vector3d> r;   // E - 1 increment residuals [rad]
  std::vector<Eigen::MatrixXd> J;   // E - 1 of 3 x n, dr/dtheta (with the Jacobian)
  // Per interval: the moments of the noise's rotation, sums over its samples
  // of w^2 {1, c, s, c^2, s^2, cs} (c, s of the recorded inner angle), and
  // the same of the sample it shares with the next interval (w_last w_first):
  // channel i's covariance per unit variance is W(u_i) = sum w^2 (P u_i)(P
  // u_i)^T with u_i = Mg^-1 e_i (WeightOf), at any Mg.
  std::vector<std::array<double, 6>> moments, cross_moments;
  // The same as matrices per interval and channel: W(u_i) at the pass's
  // Mg^-1 and at the reference's (ReduceGyro sums them scaled by each
  // channel's variance, at every noise it is asked for).
  std::vector<std::array<Eigen::Matrix3d, 3>> weights, cross_weights;
  std::vector<std::array<Eigen::Matrix3d, 3>> weights_ref, cross_weights_ref;
  Eigen::Matrix3d Mg_inv = Eigen::Matrix3d::Identity();      // at theta
  Eigen::Matrix3d Mg_inv_ref = Eigen::Matrix3d::Identity();  // at the reference
  double angle_var = 0.0;           // [rad^2] of each recorded angle
  Eigen::Vector3d K = Eigen::Vector3d::Ones();      // the gyro's scale factors at theta
  Eigen::Vector3d K_ref = Eigen::Vector3d::Ones();  // ... at the reference (prior means)
  // Per interval (with the Jacobian): the information's columns of K_x..K_z
  // and of the six angles in the readings' form (above), 3 x 9.
  std::vector<Eigen::Matrix<double, 3, 9>> J_info;
  // Per interval: false when it holds a clipped gyro sample (RunData::
  // gyro_clipped): left out, never fitted through.
  std::vector<char> valid;
  bool with_jacobian = false;
  // The run's interval the pass's first one is (EvaluateGyroPass's `first`).
  std::size_t first_interval = 0;
};

// The pass over intervals first .. first + count - 1 (all of them by
// default; count is cut at the run's end). The filter takes one interval at
// a time, each at its own estimate (gyro_measurements.h).
GyroPass EvaluateGyroPass(const RunProblem& p, const Eigen::VectorXd& theta, bool with_jacobian,
                          int threads, std::size_t first = 0,
                          std::size_t count = static_cast<std::size_t>(-1));

// The noise of interval i of the pass (its index in the pass) at the reading
// noise noise_rad_s, with the pass's weights (its scale factors and Mg^-1):
// the covariance of its residual, and of it with the next interval's (the
// epoch and the trapezoid's sample they share). ReduceGyro's blocks.
void GyroIncrementCovariance(const GyroPass& pass, std::size_t i,
                             const Eigen::Vector3d& noise_rad_s, Eigen::Matrix3d* own,
                             Eigen::Matrix3d* with_next);

struct GyroReduction {
  double cost = 0.0;       // 0.5 sum nu^T S^-1 nu at noise
  double log_det = 0.0;    // 0.5 sum log det S_e
  double neg_log_l = 0.0;  // cost + rho log_det: what the minimiser sees
  double rho = 1.0;
  Eigen::Vector3d noise_rad_s = Eigen::Vector3d::Zero();  // each channel's reading noise
  Eigen::VectorXd gradient;     // n (with the pass's Jacobian)
  Eigen::MatrixXd information;  // n x n
  int degrees_of_freedom = 0;   // 3 per interval used
  std::vector<Eigen::Vector3d> whitened;  // nu_e whitened by chol(S_e): unit white under the model
  // Per interval (with the Jacobian): its score, the gradient of what it adds
  // to the cost given the intervals before it (n), for the HAC covariance.
  std::vector<Eigen::VectorXd> scores;
};

// At a given reading noise [rad/s per channel]: cost, log-determinant, and
// with theta_part the gradient (without the weights' derivatives, which
// ReduceGyroAtNoise adds) and the information.
// mg_inv: the weights' Mg^-1 (default the pass's, at theta); without
// with_scores no per-interval scores.
GyroReduction ReduceGyro(const GyroPass& pass, const Eigen::Vector3d& noise_rad_s,
                         double rho, bool theta_part, bool with_scores = true,
                         const Eigen::Matrix3d* mg_inv = nullptr);

// At a given noise (cost and log-determinant, no theta part), and the
// gradient of -log L by the log of each channel's noise, exact: -0.5 w^T
// dSigma w (w = Sigma^-1 r, the block factorisation's back substitution)
// and rho 0.5 tr(Sigma_ref^-1 dSigma_ref) (its inverse's blocks on the band).
GyroReduction ReduceGyroWithNoiseGradient(const GyroPass& pass, const Eigen::Vector3d& noise_rad_s,
                                          double rho, Eigen::Vector3d* gradient_by_log_noise);

// At a given noise, with the theta part and the weights' derivatives in the
// gradient (what a change of the gradient at fixed noise is measured with).
GyroReduction ReduceGyroAtNoise(const GyroPass& pass, const Eigen::Vector3d& noise_rad_s,
                                double rho);

// The share of the gyro's degrees of freedom the noise estimate keeps with
// fitted_parameters estimated (the restricted likelihood's weight of the
// log-determinant), at least 0.1.
double GyroNoiseDofShare(const GyroPass& pass, int fitted_parameters);

// The noise at the maximum of the restricted likelihood (from `start`),
// reduced there (ReduceGyroAtNoise with theta_part). Its independent
// reductions (the central differences in log sigma) run on `threads`; the
// result does not depend on it.
GyroReduction ReduceGyroAtBestNoise(const GyroPass& pass, const Eigen::Vector3d& start,
                                    int fitted_parameters, bool theta_part, int threads = 1);

// The gyro's part of an estimate, for its report (fit, filter, diagnose): its
// rate noise per channel [rad/s of input rate; the readings' is |gyro.K_i|
// times it] (the fit's at the maximum likelihood; the filter's the one it
// ran at), the declared one, its increment residuals' RMS per component
// (inner, outer, normal) [rad] and whitened RMS (1 when the model holds).
struct GyroSummary {
  bool present = false;
  Eigen::Vector3d noise_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d noise_declared_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d residual_rms_rad = Eigen::Vector3d::Zero();
  double whitened_rms = 0.0;
  int degrees_of_freedom = 0;
  double neg_log_likelihood = 0.0;
  int intervals = 0;          // of interval_s
  double interval_s = 0.0;    // their mean length (about min(epoch, kGyroEpoch_s))
  int intervals_clipped = 0;  // left out: a gyro sample at the range's limit
  bool noise_auto = false;    // run.yaml gyro.noise_dps: auto (declared is the start)
  // Per interval used (the clipped ones left out), in time order: the
  // sample index of its midpoint, its increment residual (inner, outer,
  // normal) [rad] and its innovation whitened (unit white when the model
  // holds), for the residual's analysis and plot.
  std::vector<std::size_t> mid_samples;
  std::vector<Eigen::Vector3d> residual_rad, whitened;
};

// The summary of a whole pass (EvaluateGyroPass over every interval) reduced
// at some noise (red); noise_declared_rad_s and noise_auto are the caller's.
GyroSummary SummariseGyro(const RunProblem& p, const GyroPass& pass, const GyroReduction& red);

}  // namespace triadcal

// Block B1 integrated between two epochs: the velocity and position increments
// of O in L that the accelerometer samples imply, their derivatives with
// respect to theta, and the weights that carry the sample noise into them.
// Shared by the EKF (process model) and the batch solver (process residuals).
//
// Between epochs t_a = t_k0 and t_b = t_k1 the acceleration a_j = a_L(t_j) is
// taken as piecewise linear between samples (trapezoid), which integrates
// exactly to
//
//   V_b = V_a + dv,              dv = sum_j alpha_j a_j
//   S_b = S_a + V_a T + ds,      ds = sum_j beta_j a_j,        T = t_b - t_a
//
//   alpha_j = (dt_{j-1} + dt_j) / 2
//   beta_j  = [dt_j (t_b - t_{j+1}) / 2 + dt_j^2 / 3] + [dt_{j-1} (t_b - t_j) / 2 + dt_{j-1}^2 / 6]
//
// (dt_j = t_{j+1} - t_j; terms with j-1 < k0 or j >= k1 are absent). Check:
// constant a gives dv = a T, ds = a T^2 / 2. With white sample noise of
// variance s^2 on each a_j (isotropic), cov(dv, ds) = s^2 [sum a^2, sum ab;
// sum ab, sum b^2] (x) I3.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "core/model/bench_model.h"
#include "core/model/run_data.h"

namespace triadcal {

struct IntervalIncrement {
  double T_s = 0.0;
  Eigen::Vector3d dv_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d ds_m = Eigen::Vector3d::Zero();
  Eigen::MatrixXd ddv_dtheta;  // 3 x n, empty when not asked
  Eigen::MatrixXd dds_dtheta;  // 3 x n
  double sum_alpha2 = 0.0, sum_alpha_beta = 0.0, sum_beta2 = 0.0;  // noise weights
  // Covariance of (dv, ds) per unit variance [m^2/s^4] of channel i's
  // acceleration noise, which acts along the triad axis c_i = C_L2 e_i of each
  // sample: sum_j [a_j^2, a_j b_j; a_j b_j, b_j^2] (x) c_ij c_ij^T.
  std::array<Eigen::Matrix<double, 6, 6>, 3> channel_weight;
  // The first and the last sample's share of that noise, per channel
  // ((alpha, beta) (x) c_i) and for the isotropic part ((alpha, beta)): the
  // sample at an epoch ends one interval and starts the next, so neighbouring
  // intervals share its noise (cov(w_e, w_{e+1}) = sum_i s_i^2 last_i first_i^T
  // + s_iso^2 (last first^T) (x) I3; StateSpaceModel::ProcessCrossCovariance).
  std::array<Eigen::Matrix<double, 6, 1>, 3> first_channel, last_channel;
  Eigen::Vector2d first_weight = Eigen::Vector2d::Zero(), last_weight = Eigen::Vector2d::Zero();
};

// Per-sample data the increments need, prepared once per run: the run, and
// the recorded angles' rates and accelerations (EstimateAngleDerivatives)
// where the model needs them. The base model needs them at the measurement
// epochs alone (`at`): elsewhere a sample's angles are the run's own with
// rate and acceleration 0, and nothing is held per sample.
struct SampleSeries {
  const RunData* run = nullptr;
  std::vector<std::size_t> at;  // ascending sample indices; empty: every sample
  // At each of `at` (or every sample); shared by the problems of one run's
  // layouts (SharedRunWork, run_problem.h).
  std::shared_ptr<const std::vector<BenchAngles<double>>> derivatives;
  // Which readings a pass reads: the run's (every fit), or the ones the
  // model predicts at the pass's theta (PredictReadings_mV) -- the
  // Jacobian's regressors without the reading noise, for the information of
  // what a run determines -- for each sample's recorded attitude at rest
  // (rates and accelerations 0: the fit's decision, ChooseHeldParameters,
  // whose samples carry no rates between epochs), or for its recorded motion
  // (the angles' derivatives at every sample, `at` empty: observability's
  // Fisher information, the lever arm's accelerations in the readings too).
  enum class Readings { kRecorded, kPredictedAtRest, kPredicted };
  Readings readings = Readings::kRecorded;

  // Sample k's recorded angles with their rates and accelerations.
  BenchAngles<double> Recorded(std::size_t k) const;
  // Sample k's readings [mV] (`readings`).
  Eigen::Vector3d Readings_mV(const ModelConfig& cfg, const double* theta, std::size_t k,
                              const BenchAngles<double>& recorded, const SampleContext& ctx) const {
    return readings == Readings::kRecorded
               ? run->readings_mV(k)
               : PredictedReadings_mV(cfg, theta, recorded, ctx,
                                      readings == Readings::kPredictedAtRest);
  }
  // The model's readings at theta for the recorded attitude, at rest or in
  // its recorded motion.
  static Eigen::Vector3d PredictedReadings_mV(const ModelConfig& cfg, const double* theta,
                                              const BenchAngles<double>& recorded,
                                              const SampleContext& ctx, bool at_rest);

  // Samples k0, k0 + 1, ... in turn (Recorded without a search per sample).
  class Walk {
   public:
    Walk(const SampleSeries& s, std::size_t k0);
    BenchAngles<double> Next();

   private:
    const SampleSeries& s_;
    std::size_t k_, j_;  // the next sample, and the first of `at` not before it
  };
};

// Increments over samples k0..k1 (inclusive) at theta; with_jacobian fills the
// derivative blocks (b1_jacobian.h, or automatic differentiation through
// bench_model.h). with_noise fills the noise weights (sum_*, channel_weight,
// first_* and last_*): the batch solver takes them from one reference pass
// (run_evaluation.h) and skips them at every other point, where they would
// cost a bench-motion evaluation per sample. Without with_values (and without
// with_jacobian) the noise weights alone: the reference pass uses no
// increment, and they would cost a readings inverse per sample.
IntervalIncrement IntegrateInterval(const ModelConfig& cfg, const Eigen::VectorXd& theta,
                                    const SampleSeries& series, std::size_t k0, std::size_t k1,
                                    bool with_jacobian, bool with_noise = true,
                                    bool with_values = true);

// Variance of one acceleration sample [m^2/s^4] that acts alike on every axis
// of L: the angle noise rotating g, and a floor of 1e-6 m/s^2 that keeps
// noise-free runs well posed. (The reading noise acts along each triad axis:
// IntervalIncrement::channel_weight.)
double IsotropicSampleVariance(double angle_noise_rad, double g_mps2);

// Reference motion of O (block B2) at sample k and its derivatives:
// dref_dtheta is 6 x n (rows V_DU then S_DU).
struct ReferenceSample {
  Eigen::Vector3d v_mps, p_m;
  Eigen::MatrixXd dref_dtheta;
};
ReferenceSample EvaluateReference(const ModelConfig& cfg, const Eigen::VectorXd& theta,
                                  const BenchAngles<double>& recorded, bool with_jacobian);

// Covariance (6 x 6, rows V then S) of the reference motion caused by white
// angle noise sigma_angle and rate noise sigma_rate (numeric derivatives).
Eigen::Matrix<double, 6, 6> ReferenceNoiseCovariance(const ModelConfig& cfg,
                                                     const Eigen::VectorXd& theta,
                                                     const BenchAngles<double>& recorded,
                                                     double sigma_angle_rad,
                                                     double sigma_rate_rad_s);

}  // namespace triadcal

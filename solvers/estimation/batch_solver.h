// The batch solver (docs/method.md): the whole run as one sparse nonlinear
// least-squares problem, solved by Ceres.
//
// Unknowns: theta (n) and the trajectory x_e = (V_e, S_e) of O in L at the
// epochs t_e (every epoch_s, as in the filter). Residual blocks, each whitened
// by its own noise (L^T L = covariance^-1):
//
//   process, one per interval e -> e+1 (block B1 integrated, inertial_increments.h)
//     r_p = L_Q [ V_{e+1} - V_e - dv_e(theta) ;  S_{e+1} - S_e - V_e T_e - ds_e(theta) ]
//   measurement, one per epoch (block B2)
//     r_m = L_R [ V_e - V_DU(lambda, lambda', theta) ;  S_e - S_DU(lambda, theta) ]
//   constraints of run.yaml:   (c . theta - value) / sigma
//   weak priors:               (theta - nominal) / sigma_prior     (priors.h)
//
// dv_e, ds_e sum thousands of samples per interval, so they are evaluated once
// per relinearisation and enter Ceres to first order about theta_lin:
//
//   dv_e(theta) ~ dv_e(theta_lin) + J_v,e (theta - theta_lin)
//
// (as inertial preintegration does). The outer loop relinearises at Ceres's
// solution until the relinearisation changes the cost by less than
// outer_tolerance; at that fixed point the linearisation is exact at the
// solution, so it is the optimum of the full nonlinear problem (test:
// exact_increments recomputes dv_e, ds_e in every Ceres evaluation instead).
// B2, the constraints and the priors are evaluated exactly in every iteration.
//
// The Jacobian is block-banded in x plus a dense column block for theta:
// SPARSE_NORMAL_CHOLESKY (SuiteSparse CHOLMOD) by default; SPARSE_SCHUR
// eliminates every other epoch's state (the process residuals couple
// neighbours, so Ceres can only eliminate an independent set).
//
// Covariance of theta from the final Jacobian: by default the Schur complement
// on theta (schur_covariance.h, exploits the block-tridiagonal trajectory),
// or Ceres's Covariance (SuiteSparse sparse QR; the only one that applies a
// robust loss's weights). Ceres's default sparse QR fails on a rank-deficient
// Jacobian; the weak priors keep ours full rank, so directions the data do not
// determine come out with their prior sigma and are then named by
// separability.h instead of failing the factorisation.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/angle_derivatives.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/estimation/kalman_smoother.h"
#include "solvers/estimation/noise_estimation.h"
#include "core/model/priors.h"
#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/separability.h"

namespace triadcal {

enum class BatchInit { kRts, kNominal, kGiven };

// Parameters held at their nominal values. auto_hold holds those the run's
// motion does not support: a pivoted Cholesky of the data information (in
// units of the prior) at the nominal values keeps, most informative first,
// every parameter with at least min_information left once the kept ones are
// known, and holds the rest. `hold` adds to the held set, `free` removes.
// Only structural nulls are held: directions along which the data carry no
// information at all (the inner-axis rotation without its constraint, a lever
// arm along the only shaft). A parameter that is merely weakly determined is
// estimated and gets its honest, large sigma.
struct HoldPolicy {
  bool auto_hold = true;
  // In prior units at the run's full rate: 0.01 is a data sigma ten times the
  // prior's. A structural null has ~1e-4 or less at the nominal values
  // (rounding and the K_ij coupling); a weak but real direction of a short or
  // slow run has 1 or more.
  double min_information = 1e-2;
  double min_information_effects = 1e-2;
  std::vector<std::string> hold, free;
  // After the fit (auto_hold only): a parameter the data at the nominal
  // values determine at most pin_max_information times as well as its prior
  // (marginal data information in prior units, the held ones fixed) that the
  // fit moves beyond pin_excursion_sigma prior sigma is pinned at its nominal
  // value and the run refitted (SolveBatch). Under the model linearised at
  // the nominal values such a parameter's estimate moves at most
  // info/(1 + info) = 2/3 of the way to the data's value: 3 prior sigma
  // would need a nominal value wrong by 4.5 prior sigma, or the model's
  // nonlinearity following a misfit along a weak direction (real slow roll
  // run: Kxy, Kzy at -57 prior sigma with Kx 1954 mV/g and a shaft tilt of
  // 76 deg; fast run: Kxz, Kzz at +28, +22 with Kz 796 mV/g). A name in
  // `free` is never pinned.
  bool pin_weak_excursions = true;
  // Held like `hold`, but pinned by that rule: no anchor of a `relative_to`
  // (their uncertainty goes into the others' sigma instead, SolveBatch).
  std::vector<std::string> pinned;
  double pin_max_information = 2.0;
  double pin_excursion_sigma = 3.0;
};

// A parameter pinned after the fit (HoldPolicy::pin_weak_excursions): how far
// the fit had moved it, in prior sigma, and the data information about it at
// the nominal values (in prior units).
struct PinnedExcursion {
  std::string name;
  double z = 0.0;
  double data_information = 0.0;
};

struct BatchOptions {
  double epoch_s = kDefaultEpoch_s;
  AngleDerivativeOptions derivatives;
  BatchInit init = BatchInit::kRts;
  Eigen::VectorXd init_theta;   // for kGiven (SI, in the layout)
  int init_decimation_hz = 100;  // the RTS initialiser runs on samples thinned to this rate
  int max_outer_iterations = 10;
  int max_ceres_iterations = 100;
  double outer_tolerance = 1e-3;  // cost change on relinearisation, in 0.5 chi^2 units
  std::string linear_solver = "sparse_normal_cholesky";  // | sparse_schur | dense_qr
  std::string robust_loss;        // "" | huber | cauchy (on whitened process/measurement)
  double robust_scale = 3.0;      // in whitened units
  bool exact_increments = false;  // recompute B1 in every evaluation (slow; tests)
  bool compute_covariance = true;
  std::string covariance_method = "schur";  // | ceres (sparse QR; used with a robust loss)
  // Which covariance is the reported sigma (BatchResult::sigma_method):
  // "auto" (HAC when the whitened process residual is not white), "white"
  // or "hac". HAC needs the Schur covariance (not with a robust loss).
  std::string sigma = "auto";
  double hac_bandwidth_epochs = -1.0;  // < 0: Andrews's plug-in (hac_covariance.h)
  bool hac_kernel_bias_correction = true;  // hac_covariance.h
  int threads = 0;                // 0: all cores
  HoldPolicy holding;            // which parameters to hold at nominal
  // Estimate the reading noise from the residuals (noise_estimation.h) and
  // refit with it when run.yaml says `noise_mV: auto` or when the declared
  // noise is not what the residuals hold.
  bool estimate_noise = true;
  std::function<void(const std::string&)> progress;  // one line per stage
  // Estimated fraction done, 0..1, at each stage and Ceres iteration: the
  // parameter choice and start 0-0.3, relinearisation pass k from
  // 0.3 + 0.65 (1 - 2^-k), the covariance 0.95-1 (shares measured on the
  // paper's run; the number of passes is not known in advance).
  std::function<void(double)> fraction;
};

struct ResidualStats {
  Eigen::Matrix<double, 6, 1> measurement_rms = Eigen::Matrix<double, 6, 1>::Zero();  // V m/s, S m
  Eigen::Matrix<double, 6, 1> process_rms = Eigen::Matrix<double, 6, 1>::Zero();      // V m/s, S m
  // Whitened RMS of each kind. The process residuals carry nearly all the
  // degrees of freedom (expect ~1); the measurement residuals are mostly
  // absorbed by the trajectory (expect << 1).
  double measurement_whitened_rms = 0.0;
  double process_whitened_rms = 0.0;
};

struct BatchResult {
  Estimate estimate;            // theta and its covariance (SI)
  Estimate initial;             // the starting point (with the RTS sigma when from RTS)
  std::vector<std::string> held;  // held at nominal (their sigma is not an estimate)
  // The held ones that were pinned after a first fit (HoldPolicy), in the
  // order pinned; the estimate is the refit with them held.
  std::vector<PinnedExcursion> pinned;
  std::map<std::string, std::vector<std::string>> relative_to;  // HoldDecision
  // The directions the run cannot determine, found at the nominal values
  // before holding (what the held parameters stand for).
  std::vector<WeakDirection> unsupported_at_start;
  Eigen::MatrixXd information_at_start;  // HoldDecision::information
  Prior prior;
  double final_cost = 0.0;      // 0.5 sum r^2 over all blocks
  int residual_count = 0;
  // 2 cost / (residuals - unknowns): 1 when the declared noise is right and the
  // model complete (the diagnosis starts here).
  int degrees_of_freedom = 0;
  double chi2_per_dof = 0.0;
  int outer_iterations = 0, ceres_iterations = 0;
  bool converged = false;
  std::string linear_solver;
  ResidualStats residuals;
  // The reading noise per channel [mV]: as declared in run.yaml, as used for
  // the final fit and its sigma, and where that came from ("declared" |
  // "estimated" | "estimated_common"); noise_check compares the declared noise with the residuals
  // of the first fit, noise_estimate is the last estimate made.
  Eigen::Vector3d noise_declared_mV = Eigen::Vector3d::Zero();
  // noise_mV: auto (noise_declared_mV is then run.yaml's default) and the
  // level it started from (the readings' second differences, sample_noise.h).
  bool noise_auto = false;
  double noise_start_mV = 0.0;
  Eigen::Vector3d noise_used_mV = Eigen::Vector3d::Zero();
  std::string noise_source = "declared";
  // The covariance's a-posteriori variance factor: chi2/dof when the noise
  // source is "estimated_common" (every noise of the run taken as
  // sqrt(factor) times the declared one, the estimate unchanged), else 1.
  double variance_factor = 1.0;
  NoiseEstimate noise_check, noise_estimate;
  // Per epoch, for diagnosis: times, measurement and process residuals (raw,
  // V m/s then S m; the process residual of the interval ending at the epoch,
  // zero at the first), and their whitening.
  std::vector<double> epoch_t;
  std::vector<std::size_t> epoch_samples;  // sample index of each epoch
  std::vector<Eigen::Matrix<double, 6, 1>> measurement_residual, process_residual;
  std::vector<Eigen::Matrix<double, 6, 1>> measurement_whitened, process_whitened;
  // The autocorrelation (lags 1..20) that process_whitened has at this
  // solution when the model holds (ExpectedProcessAutocorrelation); empty
  // without the covariance or with a robust loss. The whiteness tests
  // subtract it.
  std::array<std::vector<double>, 6> process_whitened_expected_acf;
  // Ljung-Box on process_whitened (lags min(20, E/5), the expected
  // autocorrelation subtracted), Bonferroni over its 6 components; white when
  // p >= 0.01.
  double whiteness_p_value = 1.0;
  bool residual_white = true;
  // The two covariances of theta (n x n, SI), both at the solution: "white",
  // the inverse Fisher information of the model times variance_factor, and
  // "hac", the sandwich over the epoch scores (hac_covariance.h), which stays
  // honest when the residuals are correlated in time. estimate.cov is the one
  // named by sigma_method: "white" when the residual is white and one weight
  // fits its channels, else "hac", each parameter's variance then at least
  // its hac_floor's (the rows and columns scaled, so the matrix stays
  // positive semi-definite). cov_hac is
  // empty with the Ceres covariance (robust loss).
  std::string sigma_method = "white";
  Eigen::MatrixXd cov_white, cov_hac;
  // With "hac": what each variance is kept at least at. "white": cov_white.
  // "per_channel_bound": when one weight served channels whose residuals
  // differ beyond kMaxChannelRatio (noise_source "estimated_common", channels
  // unalike; sigma is then the HAC one even on a white residual), the
  // Cramer-Rao bound with each channel's readings at the noise its residual
  // holds (noise_check.estimated_mV) and the angles as declared.
  std::string hac_floor;
  // With pins: estimate.cov before their uncertainty was added (the
  // covariance given the pinned values). Two fits that pin the same
  // parameters at the same values share that part of their error, so their
  // difference is judged on this one (the halves of a run). Empty without
  // pins.
  Eigen::MatrixXd cov_given_pinned;
  // With pins, the consider model behind what was added (SI units, columns
  // in the order of `pinned`): pinned_sensitivity (n x pins) is the change of
  // each estimated parameter per unit change of a pinned one (zero rows for
  // held ones), pinned_cov (pins x pins) the pinned ones' marginal posterior;
  // the added covariance is S P S^T. Two fits that pin the same parameters
  // differ by (S_a - S_b) delta from the pins, which their common error
  // delta ~ P does not cancel.
  Eigen::MatrixXd pinned_sensitivity, pinned_cov;
  double hac_bandwidth_epochs = 0.0;  // the Bartlett bandwidth used, epochs
  // Whether the HAC estimate's kernel bias was corrected (hac_covariance.h),
  // and the largest factor that put on a parameter's sigma_hac.
  bool hac_kernel_bias_corrected = false;
  double hac_kernel_bias_factor_max = 1.0;
  double init_seconds = 0.0, solve_seconds = 0.0, covariance_seconds = 0.0;
  int epochs = 0;
};

// The fit. With holding.auto_hold and holding.pin_weak_excursions, a fit
// that moves weakly determined parameters beyond holding.pin_excursion_sigma
// prior sigma is repeated with them pinned at nominal (BatchResult::pinned;
// at most three refits).
BatchResult SolveBatch(const RunDescription& run, const RunData& data,
                       const ParameterLayout& layout, const BatchOptions& options);

// The parameters of fit `r` that HoldPolicy::pin_weak_excursions pins: free,
// not in policy.free, data information at the start at most
// policy.pin_max_information, beyond policy.pin_excursion_sigma prior sigma;
// largest excursion first.
// A pinned parameter is not known: the data know it at most a few times its
// prior. What its uncertainty does to the estimated parameters is added to
// r's covariances (estimate, white, HAC): a consider covariance at the
// nominal linearisation of the hold decision (r.information_at_start), the
// marginal posterior of the estimated parameters with the pinned ones free
// under their priors minus the conditional one. SolveBatch applies it.
void AddPinnedUncertainty(const ParameterLayout& layout, BatchResult* r);

// Per parameter of r's layout: the data information at the nominal values
// from r.information_at_start, marginal (the other free parameters
// estimated, r.held fixed), in prior units; 0 for a held one. Empty when the
// fit made no hold decision.
Eigen::VectorXd MarginalInformationAtStart(const ParameterLayout& layout, const BatchResult& r);

// "Kxy (-57.3, 0.21) Kzy (-56.8, 0.093)": each pin with where the first fit
// had moved it (prior sigma) and its data information at the nominal values.
std::string DescribePins(const std::vector<PinnedExcursion>& pinned);

// Whether r pinned parameter `name`.
bool IsPinned(const BatchResult& r, const std::string& name);

std::vector<PinnedExcursion> WeakExcursions(const ParameterLayout& layout, const BatchResult& r,
                                            const HoldPolicy& policy);

// The hold decision alone (what fit does first; filter uses it too). Costs one
// linearisation of the run thinned to decimation_hz.
struct HoldDecision {
  std::vector<std::string> held;
  std::vector<WeakDirection> unsupported;  // at the nominal values, before holding
  // Parameters of an undetermined direction that are estimated relative to
  // the held ones of that direction (e.g. gamma_y, gamma_z relative to
  // dlambda2 without the paper's constraint): not estimable on their own.
  std::map<std::string, std::vector<std::string>> relative_to;
  // The data information at the nominal values (n x n, full rate, prior
  // units: parameter i divided by its prior sigma), held ones included;
  // empty without auto_hold.
  Eigen::MatrixXd information;
};
HoldDecision ChooseHeldParameters(const RunDescription& run, const RunData& data,
                                  const ParameterLayout& layout, const HoldPolicy& policy,
                                  double epoch_s, const AngleDerivativeOptions& derivatives,
                                  int decimation_hz = 100, int threads = 0);

// The rule behind HoldPolicy::auto_hold, for any parameter vector: a pivoted
// Cholesky of the data information in prior units (information, n x n: each
// parameter divided by its prior sigma), most informative first, priority
// breaking near-ties in favour of the primary parameters; keeps every
// parameter with at least min_info[j] left once the kept ones are known and
// returns the kept indices. ChooseHeldParameters and the joint problem of
// several runs (solvers/multirun/) decide with it.
std::vector<int> SupportedByInformation(const Eigen::MatrixXd& information,
                                        const Eigen::VectorXd& min_info,
                                        const Eigen::VectorXd& priority);
// The priority of base or effect parameter `index` of a layout: scale
// factors and zero offsets 4, misalignments and lever arm 2, the rest 1.
double HoldPriority(int index);

}  // namespace triadcal

// The batch solver (docs/method.md section 5): the whole run as one sparse
// nonlinear least-squares problem, solved on one path.
//
// Unknowns: theta (n) and the trajectory x_e = (V_e, S_e) of O in L at the
// epochs t_e. Residual blocks, each whitened by its own noise:
//
//   process, one per interval e -> e+1 (block B1, the exact increments)
//     r_p = V_{e+1} - V_e - dv_e(theta) ;  S_{e+1} - S_e - V_e T_e - ds_e(theta)
//   measurement, one per epoch (block B2)
//     r_m = V_e - V_DU(lambda, lambda', theta) ;  S_e - S_DU(lambda, theta)
//   constraints of run.yaml:   (c . theta - value) / sigma
//   weak priors:               (theta - nominal) / sigma_prior     (priors.h)
//
// The steps of SolveBatch:
//
//   1. What the run determines, decided before the fit (ChooseHeldParameters):
//      the data information of all the samples in prior units, by a
//      pivoted Cholesky, at the nominal values (scale factors and offsets
//      fitted on the samples thinned to 25 Hz) and the declared noise (or
//      the readings' own with noise_mV: auto). A parameter the data determine at least as well as
//      its prior is estimated; one they do not stays at its nominal value,
//      its prior uncertainty carried into the others' sigma (a consider
//      covariance, as in Schmidt-Kalman filtering); one the data know nothing
//      about beyond the others (a structural null) is held and the others of
//      its direction are estimated relative to it. No misfit can move a
//      parameter that is not estimated.
//   2. The start: the EKF + RTS smoother on the samples thinned to 25 Hz (init_decimation_hz), or
//      the nominal values (also when that filter diverged: start_note says so).
//   3. The minimum (batch_minimizer.h): Levenberg-Marquardt on theta with the
//      trajectory solved for exactly at every step (run_evaluation.h) and the
//      reading noise of each channel at its maximum likelihood.
//   4. The covariance at the minimum: the model's (the inverse Gauss-Newton
//      information), the HAC sandwich over the epoch scores (hac_covariance.h),
//      and the consider term of step 1.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/angle_derivatives.h"
#include "core/model/priors.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/estimation/gyro_term.h"
#include "solvers/estimation/kalman_smoother.h"
#include "solvers/estimation/noise_estimation.h"
#include "solvers/estimation/run_problem.h"
#include "solvers/estimation/separability.h"

namespace triadcal {

enum class BatchInit { kRts, kNominal, kGiven };

// Which parameters are estimated (ChooseHeldParameters). In prior units
// (each parameter divided by its prior sigma) a pivoted Cholesky of the data
// information at the nominal values (the zero offsets fitted first) keeps
// (SupportedByInformation) every parameter the data determine, beyond the
// ones kept before it, with at least min_information and separably: those
// are estimated. The rest are not determined by the run: with less than
// null_information left they are structural nulls (held;
// the others of their direction are estimated relative to them), else
// consider parameters (held at nominal, their prior uncertainty in the
// others' sigma). `hold` holds a parameter outright (no consider term: the
// user knows it), `free` estimates one whatever its information.
struct HoldPolicy {
  bool auto_hold = true;
  // 10: the data's sigma at most a third of the prior's. With 1 (the data
  // merely as good as the prior) a misfit moves such a parameter as much as
  // the data do: real single-axis runs, declared model, Kyz at 3 prior units
  // to 0.85 /g (slow), Ky 1643 mV/g and Kyz 0.55 /g (pitch), Kxz 0.54 /g and
  // Kx 743 mV/g (fast); with 10 none of them is estimated and nothing else
  // moves beyond what its data say.
  double min_information = 10.0;
  double null_information = 1e-2;
  std::vector<std::string> hold, free;
};

// What the information of each parameter resolves to, in the units of
// `scale` (its diagonal before the states' elimination: BatchObjective::
// Point::data_information_scale). For a parameter the states absorb, the
// elimination subtracts nearly all of it and what is left is rounding, about
// 1e-16 of it (real slow roll run at the decision: dy2's 0.006 prior units
// of 3e13, above or below null_information by the order of the sums).
// kInformationResolution times that is taken as no information: the hold
// rule neither estimates nor considers a parameter on less.
constexpr double kInformationResolution = 100.0;
Eigen::VectorXd InformationResolution(const Eigen::VectorXd& scale);

// The decision of HoldPolicy (what fit does first; filter uses it too).
struct HoldDecision {
  std::vector<std::string> held;      // structural nulls and the user's holds
  std::vector<std::string> consider;  // not determined: nominal, prior uncertainty carried
  // The structural nulls at the decision point (information below
  // null_information along them), before holding.
  std::vector<WeakDirection> unsupported;
  // Parameters of an undetermined direction that are estimated relative to
  // the held ones of that direction (e.g. gamma_y, gamma_z relative to
  // dlambda2 without the paper's constraint): not estimable on their own.
  std::map<std::string, std::vector<std::string>> relative_to;
  // The data information at the nominal values (n x n, full rate, prior
  // units: parameter i divided by its prior sigma); empty without auto_hold.
  Eigen::MatrixXd information;
  // Per parameter: the data information left once the estimated ones are
  // known (prior units), what the decision compared; 0 for user holds.
  Eigen::VectorXd conditional_information;
  // Where it was decided (empty without auto_hold).
  Eigen::VectorXd theta;
};

// The estimated parameters that a fit determines only with its considered
// parameters at nominal: their consider term is more than half their
// variance, and with it they are known less than min_information times
// better than their prior. Each maps to the considered parameters (indices
// into the consider list) that carry at least a quarter of that term,
// largest first. cov includes the consider term (sensitivity S, n x c, and
// the considered parameters' prior variances: S diag(v) S^T); cov_given does
// not.
std::map<int, std::vector<int>> DeterminedOnlyWithConsidered(
    const Eigen::MatrixXd& cov, const Eigen::MatrixXd& cov_given, const Eigen::MatrixXd& sensitivity,
    const Eigen::VectorXd& consider_variance, const Eigen::VectorXd& prior_sigma,
    double min_information, const std::vector<int>& estimated);

// The bench zero of an axis that does not turn in this run and only says
// where the frame is: kDlambda2 when the inner axis's recorded angle is a
// constant (a `value:` column, a rig without that axis). A rotation about
// the inner axis is the triads' misalignments' as well (with the lever arm
// and the gyro's g-sensitivity free, nearly exactly). A run's decision holds
// it, so that the prior of a sensor that is not there does not spread into
// the misalignments (real fast roll run with its gyro: dlambda2 considered at
// +-180' left gamma_z at 40 +- 180', gyro.Gyx at -22.7 (deg/s)/g and its
// 8.6-ms latency not separable from dlambda2). The outer axis's zero is not
// one: the inner rotation lies between it and the triad, so a still outer
// axis's zero is the tilt of the inner axis, which a turning inner axis
// shows (a vertical shaft: dpsi and dtheta_c turn gravity's share across the
// shaft with it; held at 0 on a simulated shaft tilted 20', the tilt went
// into the lever arm, dz2 27 mm against the truth's 4, 25 sigma). The
// information decides it, as any parameter. A joint fit leaves the runs' own zeros to the information:
// there they also carry how each run's mounting differs from the others'.
std::vector<int> ZerosOfStillAxes(const RunData& data);

// At the nominal values with the zero offsets fitted (on the samples
// thinned to decimation_hz), at run's noise, from the information of all the
// samples there. shared: work to share with a fit of
// the same run (its weights' reference pass), or null.
HoldDecision ChooseHeldParameters(const RunDescription& run, const RunData& data,
                                  const ParameterLayout& layout, const HoldPolicy& policy,
                                  double epoch_s, const AngleDerivativeOptions& derivatives,
                                  int decimation_hz = 25, int threads = 0,
                                  SharedRunWork* shared = nullptr);

// The rule behind HoldPolicy::auto_hold, for any parameter vector: a pivoted
// Cholesky of the information in prior units (information, n x n: data and
// constraints). It keeps, highest priority first and within a priority the
// most informative first, every parameter with at least min_info[j] left
// once the kept ones are known, provided the data separate it from them
// (it keeps at least kMinSeparableShare of its own data information: one the
// kept ones explain to |rho| >= 0.99 lies along a direction where the cost is
// flat and curved, and a misfit moves it far -- real roll runs: W0y with the
// shaft tilt dpsi, which then went to 18 deg) or the constraints
// (constraint_information, may be null) give it min_info[j] by themselves.
// Returns the kept indices; `left`, when given, receives each kept
// parameter's information at its pick and each other's at the end.
std::vector<int> SupportedByInformation(const Eigen::MatrixXd& information,
                                        const Eigen::VectorXd& min_info,
                                        const Eigen::VectorXd& priority,
                                        Eigen::VectorXd* left = nullptr,
                                        const Eigen::MatrixXd* constraint_information = nullptr);
// 1 - 0.99^2: the share of its data information a parameter must keep once
// the kept ones are known (its multiple correlation with them below 0.99).
constexpr double kMinSeparableShare = 1.0 - 0.99 * 0.99;
// The priority of base or effect parameter `index` of a layout, in the order
// a calibration wants them where two explain the same data (an offset rather
// than a scale factor on an axis that always reads 1 g; an offset rather than
// a bench tilt): zero offsets 5, scale factors 4, misalignments and lever arm
// 3, nonlinearity and cross-coupling 2, bench zeros and effects 1.
double HoldPriority(int index);
// The same for any parameter of the layout (the gyro block's like the
// accelerometer's: offsets 5, scales 4, angles 3, g-sensitivity 2).
double HoldPriority(const ParameterLayout& layout, int index);

struct BatchOptions {
  double epoch_s = kDefaultEpoch_s;
  AngleDerivativeOptions derivatives;
  BatchInit init = BatchInit::kRts;
  Eigen::VectorXd init_theta;    // for kGiven (SI, in the layout)
  // The decision and the RTS start run on the samples thinned to this rate:
  // their information and start need no more (the fit's own passes use every
  // sample).
  int init_decimation_hz = 25;
  int max_iterations = 40;
  // Converged when a Gauss-Newton step would lower 0.5 chi^2 by less than
  // this (a step of sqrt(2 tolerance) sigma).
  double tolerance = 1e-4;
  bool compute_covariance = true;
  // Which covariance is the reported sigma (BatchResult::sigma_method):
  // "auto" (HAC when the whitened process residual is not white), "white"
  // or "hac".
  std::string sigma = "auto";
  double hac_bandwidth_epochs = -1.0;      // < 0: Andrews's plug-in (hac_covariance.h)
  bool hac_kernel_bias_correction = true;  // hac_covariance.h
  int threads = 0;                         // 0: all cores
  HoldPolicy holding;
  // When set, the decision of step 1 is not made but taken from here (a
  // refit of the loop keeps what the fit it starts from decided).
  const HoldDecision* decision = nullptr;
  // When set, the run's layout-independent work (the angles' derivatives,
  // the noise weights' reference pass) comes from here, formed by the first
  // fit that needs it: the fits of diagnose's loop share one (run_problem.h).
  SharedRunWork* shared = nullptr;
  // Estimate the reading noise of each channel with theta (maximum
  // likelihood; run.yaml's noise_mV is the start). Off: the noise stays as
  // given (declared, or noise_override).
  bool estimate_noise = true;
  // > 0: the noise to use [reading units], or with estimate_noise where its
  // estimate starts.
  Eigen::Vector3d noise_override = Eigen::Vector3d::Zero();
  // > 0: also the cost at the minimum with the residuals weighted by this
  // noise (BatchResult::cost_at_noise; a reduction, no pass over the
  // samples): the loop's likelihood ratio at the round's noise, from a
  // refit whose own noise is estimated.
  Eigen::Vector3d cost_at_noise = Eigen::Vector3d::Zero();
  std::function<void(const std::string&)> progress;  // one line per stage
  std::function<void(double)> fraction;              // 0..1
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
  // Not empty when the start is not the one asked for, and why (the RTS
  // smoother diverged: the nominal values, zero offsets fitted).
  std::string start_note;
  // Not estimated: the structural nulls and the user's holds (held), and the
  // parameters the run does not determine (consider); both at nominal.
  std::vector<std::string> held, consider;
  std::map<std::string, std::vector<std::string>> relative_to;  // HoldDecision
  // What the hold rule asked of a determined parameter (HoldPolicy), in prior
  // units: the reports judge the estimates' sigma by the same figure.
  double min_information = HoldPolicy().min_information;
  std::vector<WeakDirection> unsupported_at_start;
  Eigen::MatrixXd information_at_start;       // HoldDecision::information
  Eigen::VectorXd conditional_information;    // HoldDecision::conditional_information
  Prior prior;
  double final_cost = 0.0;      // 0.5 sum r^2 over all blocks
  double cost_at_noise = 0.0;   // the same at BatchOptions::cost_at_noise (when given)
  int residual_count = 0;
  // 2 cost / (residuals - unknowns): 1 when the noise is right and the model
  // complete (the diagnosis starts here).
  int degrees_of_freedom = 0;
  double chi2_per_dof = 0.0;
  bool converged = false;
  std::string termination;      // why the minimiser stopped (batch_minimizer.h)
  int iterations = 0, passes = 0;
  ResidualStats residuals;
  // The reading noise per channel [reading units]: as declared in run.yaml,
  // as used for the final fit and its sigma, and where that came from
  // ("declared" | "estimated"). noise_check compares the declared noise with
  // the estimate (its sd and degrees of freedom).
  Eigen::Vector3d noise_declared_mV = Eigen::Vector3d::Zero();
  bool noise_auto = false;        // noise_mV: auto
  Eigen::Vector3d noise_start_mV = Eigen::Vector3d::Zero();  // where the estimate started
  Eigen::Vector3d noise_used_mV = Eigen::Vector3d::Zero();
  std::string noise_source = "declared";
  NoiseEstimate noise_check;
  // Per epoch, for diagnosis: times, measurement and process residuals (raw,
  // V m/s then S m; the process residual of the interval ending at the epoch,
  // zero at the first), and their whitening.
  std::vector<double> epoch_t;
  std::vector<std::size_t> epoch_samples;  // sample index of each epoch
  std::vector<Eigen::Matrix<double, 6, 1>> measurement_residual, process_residual;
  std::vector<Eigen::Matrix<double, 6, 1>> measurement_whitened, process_whitened;
  // The autocorrelation (lags 1..20) that process_whitened has at this
  // solution when the model holds (ExpectedProcessAutocorrelation); empty
  // without the covariance. The whiteness tests subtract it.
  std::array<std::vector<double>, 6> process_whitened_expected_acf;
  // Ljung-Box on process_whitened (lags min(20, E/5), the expected
  // autocorrelation subtracted), Bonferroni over its 6 components; white when
  // p >= 0.01.
  double whiteness_p_value = 1.0;
  bool residual_white = true;
  // The covariances of theta (n x n, SI) at the solution, each with the
  // consider term: "white", the inverse Gauss-Newton information, and "hac",
  // the sandwich over the epoch scores (hac_covariance.h), honest when the
  // residuals are correlated in time. estimate.cov is the one named by
  // sigma_method ("hac" when the residual is not white, each variance then
  // at least the white one's).
  std::string sigma_method = "white";
  Eigen::MatrixXd cov_white, cov_hac;
  // estimate.cov without the consider term (the covariance given the consider
  // parameters at their nominal values), and the consider model: the
  // sensitivity of every parameter to each consider parameter (n x c, SI,
  // columns in the order of `consider`) and their prior covariance (c x c);
  // the consider term is S P S^T. Empty without consider parameters.
  Eigen::MatrixXd cov_given_consider, consider_sensitivity, consider_cov;
  // The Gauss-Newton information of the data and the constraints at the
  // solution (n x n, SI, no priors), by the estimated and considered
  // parameters (zero in the held ones' rows and columns): what the consider
  // term is read from.
  Eigen::MatrixXd information;
  double hac_bandwidth_epochs = 0.0;  // the Bartlett bandwidth used, epochs
  bool hac_kernel_bias_corrected = false;
  double hac_kernel_bias_factor_max = 1.0;
  // Wall times: init is the set-up, the decision (decide_seconds of it)
  // and the start; solve the minimiser's, of which solve_pass_seconds in its
  // passes over the samples (`passes`) and solve_reduction_seconds in its
  // `reductions` (BatchObjective::Work).
  double init_seconds = 0.0, solve_seconds = 0.0, covariance_seconds = 0.0;
  double decide_seconds = 0.0, solve_pass_seconds = 0.0, solve_reduction_seconds = 0.0;
  int reductions = 0;
  int epochs = 0;
  // The gyro triad's part (gyro_term.h), when the run has one: its noise at
  // the maximum likelihood, its residuals. final_cost and chi2_per_dof above
  // are the accelerometer's.
  using Gyro = GyroSummary;
  Gyro gyro;
};

BatchResult SolveBatch(const RunDescription& run, const RunData& data,
                       const ParameterLayout& layout, const BatchOptions& options);

// Step 1 of SolveBatch on its own: ChooseHeldParameters with options.holding
// at the noise the fit starts from (the declared noise, the readings' own
// with noise_mV: auto, or options.noise_override). The filter and `compare`
// hold what this decides, so that every estimator leaves out the same.
HoldDecision DecideHeldParameters(const RunDescription& run, const RunData& data,
                                  const ParameterLayout& layout, const BatchOptions& options);

// Whether r estimates parameter `name` (neither held nor considered).
bool IsEstimated(const BatchResult& r, const std::string& name);

// The decision a fit was made under, to refit another model under it (the
// loop's refits keep what the declared model's fit decided).
HoldDecision DecisionOf(const BatchResult& r);

// The consider term of a covariance: the parameters `est` are estimated with
// `info` (n x n, data and constraints, no priors) and their priors; the
// parameters `consider` are at their prior means with prior_sigma. Returns the
// sensitivity S (n x c: d estimate / d consider value, zero rows outside est)
// and the term S P S^T (n x n).
void ConsiderTerm(const Eigen::MatrixXd& info, const Eigen::VectorXd& prior_sigma,
                  const std::vector<int>& est, const std::vector<int>& consider,
                  Eigen::MatrixXd* sensitivity, Eigen::MatrixXd* term);

}  // namespace triadcal

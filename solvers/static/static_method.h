// The standard static method (paper Table 2, experiment 1): hold the triad
// still in several orientations in the field of gravity, average the readings
// of each position, and fit the readings model (paper eq. 1) to the averages.
//
// The orientation of a position comes from one of three references:
//
//   angles  the recorded bench angles, averaged over the position. At rest
//           (lambda' = lambda'' = 0) the specific force is gravity alone,
//             W_p = C_L2(lambda_p; dpsi, dtheta_c, dlambda2)^T (0 - g_L) / g,
//           and the lever arm drops out; the prediction is PredictReadings_mV
//           with zero rates (bench_model.h), so the bench set-up errors are
//           estimated with the triad when the positions separate them.
//             r_p = (PredictReadings_mV(theta; lambda_p) - z_p) / sigma_p
//   labels  a position label per sample (run.yaml columns.label) and the
//           direction that points up for each label (run.yaml positions,
//           default the Ferraris convention: x_p = +x up). W_p = up_p.
//             r_p = (Readings_mV(theta; W_p) - z_p) / sigma_p
//   none    no orientation: the gravity-norm fit, |W| = 1 g in every pose,
//           with W from the exact inverse of the readings model:
//             r_p = (|SpecificForceFromReadings_g(theta; z_p)| - 1) / sigma_|W|,p
//
// z_p: mean reading of position p over its N_p still samples (still_intervals.h);
// sigma_p = noise_mV / sqrt(N_p) from the declared white reading noise, and
// sigma_|W|,p = sqrt(sum_i (u_i noise_mV / K_i)^2 / N_p) with u = z_p - W0 normalised;
// with options.placement_sigma_rad the position covariance also carries the
// orientation error of the position (PositionSqrtInfo in the .cpp).
// The weak priors of priors.h (on the free parameters) and, with angles, the
// constraints of run.yaml are added as in the batch problem (docs/method.md),
// so the separability analysis (separability.h) can name what the positions do
// not support; such parameters are reported with "estimable": false.
//
// Held at their nominal value (not estimated), each with its reason:
//   angles  the lever arm dx2 dy2 dz2 (no effect at rest)
//   labels  also dpsi dtheta_c dlambda2 (no bench)
//   none    also alpha_y beta_z gamma_z: a common rotation of the triad does not
//           change |W|, so the triad frame is defined by the x accelerometer (x
//           axis) and the plane of the x and y accelerometers (xy plane), which
//           sets the three angles that turn x and y out of it to zero; and the
//           nine K_ij (the norm model is scale, bias and non-orthogonality)
//   and every name given in `fixed`.
//
// Covariance: (J^T J)^-1 of the whitened Jacobian at the solution (declared
// noise). chi2 = sum of the squared whitened position residuals, on
// dof = residuals - p_eff degrees of freedom (p_eff = trace of the hat matrix of
// the position rows: the parameters the data, not the priors, determine). The
// reported sigma is the larger of the two: declared x max(1, sqrt(chi2/dof)).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/parameters.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "core/model/priors.h"
#include "solvers/estimation/separability.h"
#include "solvers/static/still_intervals.h"

namespace triadcal {

enum class StaticReference { kAngles, kLabels, kNone };

// Labels: a position's still readings point gravity within this angle of the
// direction declared up, or the run is refused (labels swapped, wrong
// convention).
constexpr double kMaxLabelDisagreementDeg = 45.0;

const char* ReferenceName(StaticReference r);  // "angles", "labels", "none"

// "auto" picks angles when the bench angles are recorded (not constant
// channels), else labels when the run has a label column, else none. Throws
// InputError "RUN.yaml: what is missing" when the requested reference is not
// in the run, OptionError("reference", ...) for an unknown name.
StaticReference ChooseReference(const RunDescription& run, const RunData& data,
                                const std::string& requested);

struct StaticOptions {
  StillOptions still;
  std::vector<std::string> fixed;  // names held at nominal; "K_ij" stands for all nine
  // 1 sigma error of the orientation of each position that does not average out
  // over the hold (hand placement, table tilt, bench positioning), isotropic. It
  // adds sigma_o^2 D (I - u u^T) D to the covariance of the position's mean
  // reading (D = diag(K nominal), u = gravity direction); angles and labels only
  // (|W| does not depend on the orientation).
  double placement_sigma_rad = 0.0;
  int max_iterations = 200;
};

struct StaticPosition {
  std::string name;                 // the label, or P1, P2, ... in time order
  std::vector<StillInterval> intervals;  // averaged together
  std::size_t samples = 0;
  double duration_s = 0.0;          // sum over the intervals
  Eigen::Vector3d mean_mV = Eigen::Vector3d::Zero();  // z_p (platform frame)
  Eigen::Vector3d std_mV = Eigen::Vector3d::Zero();   // sample scatter
  double lambda_rad[2] = {0.0, 0.0};  // mean recorded angles (angles reference)
  Eigen::Vector3d up = Eigen::Vector3d::Zero();  // labels: W_p in the platform frame
  // At the solution:
  Eigen::Vector3d predicted_mV = Eigen::Vector3d::Zero();  // angles, labels
  Eigen::Vector3d residual_mV = Eigen::Vector3d::Zero();   // z_p - predicted
  Eigen::Vector3d residual_mg = Eigen::Vector3d::Zero();   // residual / K_i
  Eigen::Vector3d W_g = Eigen::Vector3d::Zero();           // inverse model of z_p
  double norm_residual_mg = 0.0;                           // (|W_p| - 1) in mg
};

struct HeldParameter {
  std::string name;
  std::string reason;
};

struct StaticResult {
  StaticReference reference = StaticReference::kNone;
  StillResult still;
  std::vector<StaticPosition> positions;
  ParameterLayout layout;          // the 27 base parameters
  Prior prior;
  Eigen::VectorXd theta;           // SI
  Eigen::MatrixXd cov_declared;    // from the declared noise; zero rows for held
  Eigen::MatrixXd cov;             // reported: cov_declared * sigma_scale^2
  std::vector<HeldParameter> held;
  std::vector<WeakDirection> weak;         // from cov_declared vs the priors
  std::vector<std::string> not_separable;  // parameters in `weak`
  std::vector<std::string> constraints_used, constraints_ignored;
  int data_residuals = 0;
  double effective_parameters = 0.0;  // p_eff
  double dof = 0.0, chi2 = 0.0, chi2_per_dof = 0.0;
  double sigma_scale = 1.0;           // max(1, sqrt(chi2/dof)); 1 when dof < 1
  std::string sigma_source;           // "declared noise" | "residual scatter"
  bool converged = false;
  int iterations = 0;
  double residual_rms_mg = 0.0;       // RMS over positions of residual_mg (or norm residual)
};

// The steps: held parameters for the reference; still intervals averaged into
// positions; one Ceres problem (a residual block per position, constraints,
// priors; held parameters fixed by a SubsetManifold); solve; covariance and
// chi2 from the Jacobian at the solution; residual of every position.
// Throws InputError when no position is found, OptionError (naming the
// StaticOptions / StillOptions field) when an option is out of range.
StaticResult SolveStatic(const RunDescription& run, const RunData& data,
                         StaticReference reference, const StaticOptions& options);

}  // namespace triadcal

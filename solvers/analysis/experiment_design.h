// Experiment design: the Cramer-Rao bound of a test before it is run.
//
// Quasi-harmonic runs (docs/method.md). A scenario's profile, truth and
// declared noise are simulated without noise (Simulate with the scenario's
// noise and quantization set to 0; run.yaml's declared noise kept, so the
// process and measurement weights are those of the real run) and the Fisher
// information of the batch model is evaluated at the truth
// (observability.h). Changing the profile's duration, periods or amplitudes
// and repeating gives sigma against each of them.
//
// Static multi-position test (the standard method the paper compares with).
// The bench holds P orientations (lambda1_p, lambda2_p) for duration / P each;
// the accelerometers read gravity alone (paper eq. 1 through bench_model.h with
// zero rates):
//
//   z_pk = h(theta, lambda_p) + n_pk,   n_pk ~ N(0, s^2 I3),  k = 1..N_p
//
// and the bench sets each orientation once, with a positioning error
// d_p ~ N(0, s_l^2 I2) (the run's declared angle noise) that stays for the
// whole dwell. The mean reading of position p is then sufficient, with
//
//   cov(zbar_p) = s^2 / N_p I3 + H_p s_l^2 H_p^T,   H_p = dh/dlambda (3 x 2)
//
//   I_static = sum_p J_p^T cov(zbar_p)^-1 J_p,       J_p = dh/dtheta (3 x n)
//
// (J_p and H_p by automatic differentiation through PredictReadings_mV). A
// static test has no rotation: the lever arm dR has no effect and comes out
// unobservable, as do the combinations of the bench angles and the triad
// misalignment that only motion separates. The positioning error makes sigma
// level off instead of falling as 1/sqrt(duration).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/angle_derivatives.h"
#include "core/simulation/simulator.h"
#include "solvers/estimation/observability.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

// The scenario with every source of noise in the data off (accelerometer and
// angle noise, quantization); what run.yaml declares is unchanged.
Scenario NoiseFreeScenario(const Scenario& s);

// The scenario's truth in an analysis layout, by parameter name (parameters of
// effects the scenario does not inject are 0, base parameters it does not give
// are nominal).
Eigen::VectorXd TruthInLayout(const Scenario& s, const ParameterLayout& layout);

struct DesignOptions {
  double epoch_s = kDefaultEpoch_s;
  AngleDerivativeOptions derivatives;
  ObservabilityOptions observability;
};

// The observability of the scenario's run (noise-free, at its truth).
ObservabilityResult AnalyseScenario(const Scenario& s, const ParameterLayout& layout,
                                    const DesignOptions& opt);

// CRB of one design: sigma per parameter (SI) with the run's constraints and
// priors, and the parameters in unobservable directions.
struct DesignPoint {
  double duration_s = 0.0;
  Eigen::VectorXd sigma;                   // SI
  std::vector<std::string> unobservable;   // parameter names
  std::vector<WeakDirection> directions;   // the unobservable directions
};

// The scenario's quasi-harmonic run with this profile.
DesignPoint EvaluateProfile(const Scenario& s, const HarmonicProfile& profile,
                            const ParameterLayout& layout, const DesignOptions& opt);

// Bench orientations (lambda1, lambda2) [rad] of a static test. count = 6:
// each triad axis up and down; 18: those and the 12 orientations with gravity
// at 45 deg between two axes (all sign combinations); 12: the 6 and the 6 of
// those 12 with gravity in the first quadrant of each axis pair and its
// opposite. Throws OptionError("static_positions", ...) for another count.
std::vector<std::array<double, 2>> StaticPositions(int count);

// Fisher information of a static test (see above), SI.
Eigen::MatrixXd StaticTestInformation(const RunDescription& run, const ParameterLayout& layout,
                                      const Eigen::VectorXd& theta,
                                      const std::vector<std::array<double, 2>>& positions,
                                      double duration_s, double rate_hz);

// The static test as a design point (with the run's constraints and priors).
DesignPoint EvaluateStatic(const Scenario& s, const ParameterLayout& layout,
                           const std::vector<std::array<double, 2>>& positions, double duration_s,
                           const ObservabilityThresholds& t);

// Parameter groups for summaries: name, unit and member indices (base layout).
struct ParameterGroup {
  std::string name;   // "K", "W0", "angles", "K_ij", "bench", "dR"
  std::string label;  // "scale factors K", ...
  std::vector<int> members;
};
const std::vector<ParameterGroup>& ParameterGroups();

// Indices named by a target key: a parameter name or a group name.
// Throws OptionError("targets", ...) naming the key when it is neither.
std::vector<int> TargetIndices(const ParameterLayout& layout, const std::string& key);

// The shortest duration of the scenario's profile for which the worst sigma of
// `indices` is <= sigma_target_si, by bisection on log(duration) between
// t_min and t_max (CRB evaluations, relative resolution `resolution`).
struct TargetResult {
  double duration_s = 0.0;  // t_max when not reached
  bool reached = false;
  double sigma_at_duration = 0.0;  // SI, worst of the indices
  int evaluations = 0;
};
TargetResult DurationForTarget(const Scenario& s, const ParameterLayout& layout,
                               const std::vector<int>& indices, double sigma_target_si,
                               double t_min, double t_max, const DesignOptions& opt,
                               double resolution = 0.01);

}  // namespace triadcal

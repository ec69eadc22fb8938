// One run through the paper's EKF and RTS smoother as `triadcal filter` does
// it (solvers/estimation/kalman_smoother.h): the settings, the hold decision
// of the fit job, the filter, and the OUT.json. The command prints it.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "app/run_loading.h"
#include "app/session.h"
#include "core/model/angle_derivatives.h"
#include "core/model/parameters.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/kalman_smoother.h"

namespace triadcal {

// At most this many smoother passes (--iterations): each is a whole EKF + RTS
// pass over the run, and the relinearised estimate settles in two or three
// (1e9 ran on without end).
constexpr int kMaxFilterIterations = 20;

// The settings of a filter run, each default declared here once.
struct FilterSettings {
  std::string effects;               // catalogue effects to estimate too, "a,b"
  double epoch_s = kDefaultEpoch_s;  // [s]
  double rate_window_s = AngleDerivativeOptions().half_window_s;  // [s]
  int iterations = FilterOptions().smoother_iterations;           // 1 .. kMaxFilterIterations
  bool correlations = false;  // the RTS correlation matrix in OUT
  bool keep_series = false;   // the forward pass against time (FilterSeriesCsv)
  // What fit holds, held (absent from the filter's state): the structural
  // nulls and the parameters the run does not determine; and the user's.
  bool auto_hold = true;
  std::vector<std::string> hold, free;  // parameter names

  // Throws InputError naming the option (as the command line's flag) for a
  // bad setting, before any work.
  void Validate() const;
};

struct FilterOutcome {
  ParameterLayout layout;
  FilterResult result;
  // The fit job's decision (DecideHeldParameters): held and considered are
  // both held at nominal here (the filter carries no consider covariance).
  HoldDecision decision;
  std::vector<std::string> pinned;      // held at nominal: decision.held + decision.consider
  std::vector<WeakDirection> weak;      // directions the run leaves to the prior
  std::set<std::string> not_estimable;  // prior values: weak, pinned and relative ones
  // The run has a gyro (block and columns): its parameters are in the
  // layout and the filter takes its increments (result.gyro); OUT's "gyro"
  // is fit's block (FilterGyroJson).
  bool gyro = false;
  // The reading noise it ran at, per channel, in the readings' unit: the
  // declared one, or with noise_mV: auto the readings' own (RunReadingNoise_mV).
  Eigen::Vector3d noise = Eigen::Vector3d::Zero();
  double seconds = 0.0;                 // the decision and the filter
  // Not empty when the filter diverged (its covariance lost its positive
  // definiteness, FilterResult::diverged_at_s, or its estimate is not finite): the reason,
  // one sentence; then there is no OUT (json is null).
  std::string error;
  nlohmann::json json;  // OUT.json of `filter` (without the provenance its writer adds)
};

// Validates the settings and filters `run` (read from run_yaml); progress
// goes to the session's callbacks ("pass 1/2" and the fraction done).
FilterOutcome FilterRun(const FilterSettings& s, const std::string& run_yaml, const LoadedRun& run,
                        const Session& session);

// OUT's "gyro" of a filter that took the run's gyro (f.gyro): fit's block
// (fit_report.h GyroJson, AddGyroAnalysis: the same keys) for the smoother's
// estimate: its residuals whitened at the noise the filter ran at
// ("noise": "used_dps", "source" declared or the readings' own), the noise
// the fit would estimate there ("estimated_dps"), and "mean_nis" of its
// measurements (3 expected).
nlohmann::json FilterGyroJson(const RunDescription& run, const RunData& data,
                              const FilterOutcome& f);

// The forward pass (FilterResult::series) as CSV: each parameter and its
// sigma in file units, the innovations and theirs, against time.
std::string FilterSeriesCsv(const ParameterLayout& layout, const FilterResult& r);

}  // namespace triadcal

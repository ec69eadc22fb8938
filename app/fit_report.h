// What `fit` and `compare` say about a batch solution: the verdict line, the
// parameters the run cannot separate or that sit at their prior, and the OUT
// JSON (the printed table: tools/report/fit_table.h).
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "solvers/diagnosis/residual_analysis.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/separability.h"

namespace triadcal {

struct FitReport {
  std::vector<WeakDirection> weak;
  std::set<std::string> not_estimable;  // held, or in a weak direction
  std::set<std::string> held;
  std::set<std::string> consider;  // not determined: nominal, prior uncertainty carried
  // Estimated, but determined only together with considered parameters:
  // sigma above the prior's / sqrt(BatchResult::min_information) (what the
  // hold rule asks of a determined parameter), mostly from the considered
  // ones' prior uncertainty (more than half the variance). The value holds
  // for the considered ones at nominal; named with the considered parameters
  // that carry most of it (e.g. gamma_z with gamma_y on a roll run).
  std::map<std::string, std::vector<std::string>> with_considered;
  // > 3 prior sigma from the nominal value, largest |z| first (JSON
  // "at_prior_bound" and verdict.beyond_prior: their names).
  std::vector<PriorExcursion> beyond_prior;
  std::string verdict;  // the sentence
  // The verdict machines read: residual_white is a Ljung-Box test of each
  // whitened process-residual channel (Bonferroni over the 6, alpha 1 %);
  // pass = converged and residual_white.
  bool residual_white = true;
  double whiteness_p_value = 1.0;  // smallest channel p-value x 6 (capped at 1)
  bool noise_consistent = true;
  bool pass = true;
};

// The gyro triad's own verdict (SPEC section 10), from its increment
// residuals (gyro_residuals: AnalyzeGyroResiduals of the same fit): white by
// the accelerometer's rule (Ljung-Box of each whitened component, Bonferroni
// over the 3, white when p >= 0.01); pass = converged and white. The gyro's
// parameters held, not determined (considered), not separable and beyond 3
// prior sigma are named; the sentence says all of it with the rate noise in
// the readings' unit (deg/s).
struct GyroVerdict {
  bool residual_white = true;
  double whiteness_p_value = 1.0;  // smallest component p-value x 3 (capped at 1)
  bool pass = true;
  std::vector<std::string> held, not_determined, not_separable, beyond_prior;
  std::string sentence;
};
GyroVerdict MakeGyroVerdict(const ParameterLayout& layout, const BatchResult& r,
                            const FitReport& rep, const ResidualReport& gyro_residuals);
nlohmann::json GyroVerdictJson(const GyroVerdict& v);

// The gyro's part of a fit's OUT (r.gyro.present): its noise in deg/s, the
// increment residuals' RMS, intervals and degrees of freedom; and, added to
// it from the run, its verdict, residual analysis and plot (what `fit` and
// each state of `diagnose` write under "gyro").
nlohmann::json GyroJson(const ParameterLayout& layout, const BatchResult& r);
void AddGyroAnalysis(const RunDescription& run, const RunData& data, const ParameterLayout& layout,
                     const BatchResult& r, const FitReport& rep, nlohmann::json* gyro);

// Exit status of a fit that did not converge, and of a failed --require
// check (bad input exits 2, an internal error 3).
constexpr int kExitNotConverged = 4;
constexpr int kExitRequirementFailed = 5;

FitReport MakeFitReport(const ParameterLayout& layout, const BatchResult& r);
nlohmann::json FitJson(const ParameterLayout& layout, const BatchResult& r, const FitReport& rep,
                       bool correlations);
// out["consider"]: r.consider as [{parameter, prior_sigma, data_information,
// sensitivity}] (the consider model in file units), and on each in
// out["parameters"] (which must be written) its prior sigma as "sigma",
// "determined": false and "considered": true.
void AddConsiderJson(const ParameterLayout& layout, const BatchResult& r, nlohmann::json* out);

}  // namespace triadcal

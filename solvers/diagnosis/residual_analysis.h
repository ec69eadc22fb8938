// What a batch fit leaves in its residuals, in physical units: per channel the
// RMS, whiteness (Ljung-Box), the spectrum's strongest peaks with the bench
// frequencies and their combinations marked, and the correlation with the
// kinematic signals (angles, rates, angular accelerations, time, temperature).
//
// Channels: the process residual of each interval (block B1 integrated minus
// the trajectory) expressed as a mean acceleration in the triad frame,
//   a_res = C_L2(mid)^T r_V / T / g        [mg]
// (this is where a missing sensor or angle effect shows), and the whitened
// process residuals in L (for whiteness against the declared noise). With a
// gyro triad, the same analysis of its attitude increment residuals
// (AnalyzeGyroResiduals).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/statistics/statistics.h"

namespace triadcal {

struct SpectralPeak {
  double freq_hz = 0.0;
  double power_fraction = 0.0;  // of the channel's total variance
  std::string combination;      // e.g. "2 f1 + f2", or "" when none is near
};

struct ChannelReport {
  std::string name, unit;
  double rms = 0.0;
  double mean = 0.0;
  WhitenessTest whiteness;
  bool tested = false;              // enters the whiteness decision (the whitened channels)
  std::vector<SpectralPeak> peaks;  // strongest first
  std::vector<std::pair<std::string, double>> correlations;  // |r| largest first
  std::vector<double> series;  // the channel per interval (ResidualReport::t_s), for plots
};

struct ResidualReport {
  // What the channels' series are (the plot's title) and their unit: the
  // channels in this unit are plotted (residual_plot_json.h).
  std::string series_what, series_unit;
  std::vector<ChannelReport> channels;
  double chi2_per_dof = 0.0;
  int degrees_of_freedom = 0;
  double f1_hz = 0.0, f2_hz = 0.0;  // bench frequencies found in the angles
  std::vector<double> t_s;          // interval midpoints of the channel series [s]
  double dt_s = 0.0;                // their mean spacing (the periodogram's)
  // Evidence of structure: a channel's Ljung-Box p below this, or chi2/dof
  // more than 4 standard deviations above 1.
  double whiteness_alpha = 1e-3;
  bool structure = false;
  std::string structure_summary;  // one sentence when structure is present
};

ResidualReport AnalyzeResiduals(const RunDescription& run, const RunData& data,
                                const ParameterLayout& layout, const BatchResult& fit);

// The gyro triad's increment residuals (gyro_term.h; fit.gyro), the same
// analysis: channels "gyro increment residual inner|outer|normal" [arcsec]
// with spectrum and correlations, and the innovations whitened [1], which
// decide whiteness (Ljung-Box, no autocorrelation expected); chi2/dof the
// whitened RMS squared. Empty (no channels) without a gyro.
ResidualReport AnalyzeGyroResiduals(const RunDescription& run, const RunData& data,
                                    const ParameterLayout& layout, const BatchResult& fit);

nlohmann::json ResidualReportJson(const ResidualReport& r);

}  // namespace triadcal

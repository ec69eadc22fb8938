// What the HTML report draws of a fit's residual, stored in OUT.json under
// "residual_plot": the process residual per interval as a mean acceleration
// in the triad frame (mg, the diagnosis channels of residual_analysis.h), its
// periodogram, and the bench frequencies to mark on it. With a gyro triad,
// "gyro": {"residual_plot": ...} the same of its attitude increment
// residuals (arcsec). The channels drawn are those in r.series_unit.
//
// Long series are thinned so OUT stays small whatever the run's length: the
// time series keeps the minimum and the maximum of each bucket (in their time
// order, so spikes survive), the spectrum the largest power of each bucket
// (so peaks survive). Each is at most 2 * max_points long; values keep 4
// significant digits (times 7, frequencies 6, powers 3).
#pragma once

#include <nlohmann/json.hpp>

#include "solvers/diagnosis/residual_analysis.h"

namespace triadcal {

nlohmann::json ResidualPlotJson(const ResidualReport& r, int max_points = 600);

}  // namespace triadcal

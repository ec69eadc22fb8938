// Still intervals of a run: where the triad rests, so that the static method
// (static_method.h) can average its readings.
//
// Two tests of "still" at sample k:
//
//   angle rates    (bench angles recorded)  |lambda1'| and |lambda2'| below
//                  rate_threshold; lambda' from the rate columns or the local
//                  cubic fit of angle_derivatives.h. The default threshold is
//                  max(0.05 deg/s, 5 sigma of the estimated rate).
//   reading variance (no angles)  over the centred window of window_s, the
//                  standard deviation of each of wx, wy, wz below
//                  noise_factor x the declared reading noise (run.yaml
//                  triad.noise_mV). A window of n white samples estimates sigma
//                  to ~1/sqrt(2n) (10 % for 50 samples): the default factor 2 is
//                  far above that scatter and far below the motion of a handled
//                  IMU (hundreds of counts).
//
// Runs of still samples separated by at most merge_gap_s are merged (one
// outlier sample does not split a position), edge_s is dropped at each end
// (the settling of the sensor and of a hand), and what is shorter than
// min_still_s is dropped. With a label channel and position labels given, an
// interval never crosses a change of label, and samples whose label is not a
// position are never still (without position labels the labels are ignored).
#pragma once

#include <cstddef>
#include <set>
#include <string>
#include <vector>

#include "core/model/run_data.h"

namespace triadcal {

enum class StillTest { kAngleRates, kReadingVariance };

struct StillOptions {
  double min_still_s = 1.0;
  double edge_s = 0.2;
  double merge_gap_s = 0.2;
  double window_s = 0.5;              // reading variance: centred window
  double noise_factor = 2.0;          // reading variance: threshold / declared noise
  double rate_threshold_deg_s = 0.0;  // angle rates: 0 = max(0.05, 5 sigma of lambda')
  double rate_half_window_s = 0.1;    // angle rates: local cubic fit half window
  // Upper bounds (a still hold lasts seconds to a minute): window_s, edge_s
  // and merge_gap_s at most 10 minutes, min_still_s an hour.
  static constexpr double kMaxWindow_s = 600.0;
  static constexpr double kMaxMinStill_s = 3600.0;
  static constexpr double kMaxNoiseFactor = 1e4;
  static constexpr double kMaxRateThreshold_deg_s = 3600.0;
};

// Throws OptionError naming the StillOptions field of a setting out of range
// (the command adds its flag).
void CheckStillOptions(const StillOptions& options);

struct StillInterval {
  std::size_t begin = 0, end = 0;  // samples [begin, end)
  double t_begin_s = 0.0, t_end_s = 0.0;  // first and last sample
  std::string label;               // the position label, "" without labels
  std::size_t samples() const { return end - begin; }
  double duration_s() const { return t_end_s - t_begin_s; }
};

struct StillResult {
  StillTest test = StillTest::kReadingVariance;
  std::vector<StillInterval> intervals;
  double threshold = 0.0;        // deg/s (angle rates) or mV (reading variance: the std limit)
  std::size_t window_samples = 0;  // reading variance
  std::size_t dropped_short = 0;   // still runs shorter than min_still_s after the edges
};

// position_labels: the labels that are positions (others are never still);
// empty: labels are not used. angle_noise_rad sets the default rate
// threshold. Throws OptionError naming the StillOptions field for options
// out of range.
StillResult FindStillIntervals(const RunData& data, StillTest test, double noise_mV,
                               double angle_noise_rad, const std::set<std::string>& position_labels,
                               const StillOptions& options);

}  // namespace triadcal

// Still-interval detection (still_intervals.h): a per-sample still flag from
// the angle rates or the moving variance of the readings, then runs of still
// samples merged, trimmed and filtered by length.
#include "solvers/static/still_intervals.h"

#include <algorithm>
#include <cmath>

#include "core/model/angle_derivatives.h"
#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

double MedianInterval_s(const std::vector<double>& t) {
  std::vector<double> dt(t.size() - 1);
  for (std::size_t k = 1; k < t.size(); ++k) dt[k - 1] = t[k] - t[k - 1];
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

// Moving standard deviation over the centred window of w samples (shorter at
// the ends), from prefix sums of x - x[0] (no cancellation at count levels).
std::vector<double> MovingStd(const std::vector<double>& x, std::size_t w) {
  const std::size_t n = x.size();
  std::vector<double> s1(n + 1, 0.0), s2(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    const double d = x[k] - x[0];
    s1[k + 1] = s1[k] + d;
    s2[k + 1] = s2[k] + d * d;
  }
  std::vector<double> out(n);
  const std::size_t half = w / 2;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t lo = k >= half ? k - half : 0;
    const std::size_t hi = std::min(n, lo + w);
    const double m = static_cast<double>(hi - lo);
    const double mean = (s1[hi] - s1[lo]) / m;
    const double var = (s2[hi] - s2[lo]) / m - mean * mean;
    out[k] = std::sqrt(std::max(0.0, var * m / std::max(1.0, m - 1.0)));
  }
  return out;
}

}  // namespace

// Bad settings name the StillOptions field (OptionError); the command adds its flag.
void CheckStillOptions(const StillOptions& o) {
  auto require = [](bool ok, const char* option, const char* problem) {
    if (!ok) throw OptionError(option, problem);
  };
  // The lower bounds first (their wording is older), then the upper ones,
  // which also refuse infinities (a still hold lasts seconds to a minute).
  using S = StillOptions;
  require(o.min_still_s > 0.0, "min_still_s", "must be > 0");
  require(o.min_still_s <= S::kMaxMinStill_s, "min_still_s", "must be at most 3600 s");
  require(o.edge_s >= 0.0, "edge_s", "must be >= 0");
  require(o.edge_s <= S::kMaxWindow_s, "edge_s", "must be at most 600 s");
  require(o.merge_gap_s >= 0.0, "merge_gap_s", "must be >= 0");
  require(o.merge_gap_s <= S::kMaxWindow_s, "merge_gap_s", "must be at most 600 s");
  require(o.window_s > 0.0, "window_s", "must be > 0");
  require(o.window_s <= S::kMaxWindow_s, "window_s", "must be at most 600 s");
  require(o.noise_factor > 0.0, "noise_factor", "must be > 0");
  require(o.noise_factor <= S::kMaxNoiseFactor, "noise_factor", "must be at most 10000");
  require(o.rate_threshold_deg_s >= 0.0, "rate_threshold_deg_s", "must be >= 0 (0: automatic)");
  require(o.rate_threshold_deg_s <= S::kMaxRateThreshold_deg_s, "rate_threshold_deg_s",
          "must be at most 3600 deg/s");
  require(o.rate_half_window_s > 0.0, "rate_half_window_s", "must be > 0");
  AngleDerivativeOptions d;
  d.half_window_s = o.rate_half_window_s;
  try {
    d.Check();
  } catch (const OptionError& e) {
    throw OptionError("rate_half_window_s", e.problem());
  }
}

StillResult FindStillIntervals(const RunData& data, StillTest test, double noise_mV,
                               double angle_noise_rad, const std::set<std::string>& position_labels,
                               const StillOptions& o) {
  CheckStillOptions(o);
  StillResult r;
  r.test = test;
  const std::size_t n = data.size();
  if (n < 3) return r;
  const double dt = MedianInterval_s(data.t_s);

  // Per-sample still flag.
  std::vector<char> still(n, 1);
  if (test == StillTest::kAngleRates) {
    AngleDerivativeOptions d;
    d.half_window_s = o.rate_half_window_s;
    double threshold_rad_s = o.rate_threshold_deg_s * kDegToRad;
    if (threshold_rad_s == 0.0) {
      const double sigma_rate = data.has_rates() ? 0.0 : RateNoiseGain(dt, d) * angle_noise_rad;
      threshold_rad_s = std::max(0.05 * kDegToRad, 5.0 * sigma_rate);
    }
    r.threshold = threshold_rad_s / kDegToRad;
    const std::vector<BenchAngles<double>> b = EstimateAngleDerivatives(data, d);
    for (std::size_t k = 0; k < n; ++k) {
      still[k] = std::abs(b[k].axis[0].rate) < threshold_rad_s &&
                 std::abs(b[k].axis[1].rate) < threshold_rad_s;
    }
  } else {
    const std::size_t w = std::max<std::size_t>(3, std::lround(o.window_s / dt));
    r.window_samples = w;
    r.threshold = o.noise_factor * noise_mV;
    for (int i = 0; i < 3; ++i) {
      const std::vector<double> s = MovingStd(data.w_mV[i], w);
      for (std::size_t k = 0; k < n; ++k) still[k] = still[k] && s[k] < r.threshold;
    }
  }
  const bool by_label = data.has_label() && !position_labels.empty();
  if (by_label) {
    for (std::size_t k = 0; k < n; ++k) {
      still[k] = still[k] && position_labels.count(data.label[k]) > 0;
    }
  }
  auto same_label = [&](std::size_t a, std::size_t b) {
    return !by_label || data.label[a] == data.label[b];
  };

  // Runs of still samples [begin, end), never across a label change.
  std::vector<StillInterval> runs;
  for (std::size_t k = 0; k < n;) {
    if (!still[k]) {
      ++k;
      continue;
    }
    StillInterval iv;
    iv.begin = k;
    while (k < n && still[k] && same_label(iv.begin, k)) ++k;
    iv.end = k;
    runs.push_back(iv);
  }
  // Merge runs separated by short gaps (same label only).
  std::vector<StillInterval> merged;
  for (const StillInterval& iv : runs) {
    if (!merged.empty()) {
      StillInterval& last = merged.back();
      const double gap_s = data.t_s[iv.begin] - data.t_s[last.end - 1];
      if (gap_s <= o.merge_gap_s + 0.5 * dt && same_label(last.begin, iv.begin)) {
        last.end = iv.end;
        continue;
      }
    }
    merged.push_back(iv);
  }
  // Drop the edges, then what is too short.
  for (StillInterval iv : merged) {
    const double t0 = data.t_s[iv.begin] + o.edge_s, t1 = data.t_s[iv.end - 1] - o.edge_s;
    while (iv.begin < iv.end && data.t_s[iv.begin] < t0 - 1e-9 * std::abs(t0)) ++iv.begin;
    while (iv.end > iv.begin && data.t_s[iv.end - 1] > t1 + 1e-9 * std::abs(t1)) --iv.end;
    if (iv.end <= iv.begin + 1) {
      ++r.dropped_short;
      continue;
    }
    iv.t_begin_s = data.t_s[iv.begin];
    iv.t_end_s = data.t_s[iv.end - 1];
    if (iv.duration_s() + dt < o.min_still_s) {
      ++r.dropped_short;
      continue;
    }
    if (by_label) iv.label = data.label[iv.begin];
    r.intervals.push_back(iv);
  }
  return r;
}

}  // namespace triadcal

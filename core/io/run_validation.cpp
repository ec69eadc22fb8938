// Validation of run data as read: fatal checks and counted warnings.
#include "core/io/run_validation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {

namespace {

// Short human number: 4 significant digits.
std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", x);
  return buf;
}

double Span(const std::vector<double>& v) {
  if (v.empty()) return 0.0;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

// Samples equal to `extreme` that sit in runs of at least 3 equal samples.
std::size_t HeldInRuns(const std::vector<double>& v, double extreme) {
  std::size_t held = 0, run = 0;
  for (std::size_t k = 0; k <= v.size(); ++k) {
    if (k < v.size() && v[k] == extreme) {
      ++run;
      continue;
    }
    if (run >= 3) held += run;
    run = 0;
  }
  return held;
}

}  // namespace

void CheckSampleCount(const DataTable& table, std::size_t n, const std::string& what) {
  if (n < kMinSamples) {
    throw InputError(table.path + ": only " + std::to_string(n) + " " + what + " (at least " +
                     std::to_string(kMinSamples) + " needed)");
  }
}

void CheckFinite(const DataTable& table, const std::vector<const ChannelValues*>& channels) {
  std::size_t first_row = table.rows;
  const ChannelValues* first = nullptr;
  for (const ChannelValues* c : channels) {
    for (std::size_t k = 0; k < c->values.size() && k < first_row; ++k) {
      if (!std::isfinite(c->values[k])) {
        first_row = k;
        first = c;
        break;
      }
    }
  }
  if (!first) return;
  const double v = first->values[first_row];
  throw InputError(table.Where(first_row) + ": " + first->label + ": " +
                   (std::isnan(v) ? "NaN" : "infinite value") + " (every sample must be a number)");
}

void CheckTimeNotDecreasing(const DataTable& table, const ChannelValues& t) {
  const std::vector<double>& v = t.values;
  for (std::size_t k = 1; k < v.size(); ++k) {
    if (v[k] < v[k - 1]) {
      throw InputError(table.Where(k) + ": " + t.label + ": time decreases from " + Num(v[k - 1]) +
                       " s to " + Num(v[k]) + " s");
    }
  }
}

void CheckReadingsInMillivolts(const DataTable& table, const ChannelValues& w,
                               double nominal_range_mV) {
  const double limit_mV = 0.02 * nominal_range_mV;
  for (double x : w.values) {
    if (std::abs(x) >= limit_mV) return;
  }
  throw InputError(table.path + ": " + w.label + ": every |value| is below " + Num(limit_mV) +
                   " mV (2% of the nominal scale + |bias|): looks like V or g, not mV; set "
                   "columns." +
                   w.name + ".unit");
}

void CheckAnglesInDegrees(const DataTable& table, const ChannelValues (&lambda)[2],
                          const ChannelValues (&w)[3], const double (&scale_mV_per_g)[3]) {
  const double limit = 2.0 * kPi + 0.1;
  const double span[2] = {Span(lambda[0].values), Span(lambda[1].values)};
  if (span[0] >= limit || span[1] >= limit) return;
  for (int i = 0; i < 3; ++i) {
    const double swing_mV = Span(w[i].values);
    if (swing_mV > 0.5 * scale_mV_per_g[i]) {
      throw InputError(table.path + ": " + lambda[0].label + ", " + lambda[1].label +
                       ": spans of only " + Num(span[0]) + " and " + Num(span[1]) + " deg while " +
                       w[i].name + " swings by " + Num(swing_mV / scale_mV_per_g[i]) +
                       " g: the angles look like radians, not degrees; set "
                       "columns.lambda1.unit and columns.lambda2.unit to rad");
    }
  }
}

std::vector<std::size_t> FirstOfEqualTimes(const std::vector<double>& t_s) {
  std::vector<std::size_t> keep;
  keep.reserve(t_s.size());
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    if (k == 0 || t_s[k] != t_s[k - 1]) keep.push_back(k);
  }
  return keep;
}

std::optional<std::string> DuplicateWarning(std::size_t n_dropped) {
  if (n_dropped == 0) return std::nullopt;
  return std::to_string(n_dropped) +
         " samples with a repeated time stamp dropped (kept the first of each)";
}

std::optional<std::string> GapWarning(const std::vector<double>& t_s) {
  if (t_s.size() < 3) return std::nullopt;
  // One copy of the intervals, for the median; each is formed again below.
  auto dt = [&t_s](std::size_t k) { return t_s[k + 1] - t_s[k]; };
  std::vector<double> sorted(t_s.size() - 1);
  for (std::size_t k = 0; k < sorted.size(); ++k) sorted[k] = dt(k);
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::size_t count = 0, largest_at = 0;
  for (std::size_t k = 0; k < sorted.size(); ++k) {
    if (dt(k) > 1.5 * median) {
      ++count;
      if (dt(k) > dt(largest_at) || dt(largest_at) <= 1.5 * median) largest_at = k;
    }
  }
  if (count == 0) return std::nullopt;
  return std::to_string(count) + " gaps in time (intervals > 1.5x the median interval " +
         Num(median) + " s); the largest is " + Num(dt(largest_at)) +
         " s, after t = " + Num(t_s[largest_at]) + " s";
}

std::optional<std::string> SaturationWarning(const ChannelValues& c, const std::string& unit) {
  const std::vector<double>& v = c.values;
  if (v.empty()) return std::nullopt;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  if (*hi == *lo) return std::nullopt;  // constant: CheckConstantChannels says so
  const double min_threshold = 0.001 * static_cast<double>(v.size());
  std::string out;
  for (const auto& [extreme, word] : {std::pair{*hi, "maximum"}, std::pair{*lo, "minimum"}}) {
    const std::size_t held = HeldInRuns(v, extreme);
    if (held == 0 || static_cast<double>(held) < min_threshold) continue;
    if (!out.empty()) out += "; ";
    out += std::to_string(held) + " samples (" + Num(100.0 * held / v.size()) + "%) at its " +
           word + " " + Num(extreme) + " " + unit + " in runs of 3 or more";
    if (*hi == *lo) break;
  }
  if (out.empty()) return std::nullopt;
  return c.label + " may be saturated or clipped: " + out;
}

std::size_t MarkClipped(const ChannelValues& c, std::vector<char>* clipped) {
  const std::vector<double>& v = c.values;
  if (v.empty()) return 0;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  if (*hi == *lo) return 0;
  const double min_threshold = 0.001 * static_cast<double>(v.size());
  std::size_t marked = 0;
  for (const double extreme : {*hi, *lo}) {
    const std::size_t held = HeldInRuns(v, extreme);
    if (held == 0 || static_cast<double>(held) < min_threshold) continue;
    std::size_t run = 0;
    for (std::size_t k = 0; k <= v.size(); ++k) {
      if (k < v.size() && v[k] == extreme) {
        ++run;
        continue;
      }
      if (run >= 3) {
        for (std::size_t j = k - run; j < k; ++j) {
          if (!(*clipped)[j]) ++marked;
          (*clipped)[j] = 1;
        }
      }
      run = 0;
    }
  }
  return marked;
}

void UnwrapDegrees(std::vector<double>* deg) {
  std::vector<double>& v = *deg;
  double shift = 0.0, previous = v.empty() ? 0.0 : v[0];
  for (std::size_t k = 1; k < v.size(); ++k) {
    const double raw = v[k];
    const double jump = raw - previous;
    if (std::abs(jump) > 180.0) shift -= 360.0 * std::round(jump / 360.0);
    previous = raw;
    v[k] = raw + shift;
  }
}

}  // namespace triadcal

#include "app/residual_plot_json.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "solvers/statistics/statistics.h"

namespace triadcal {
namespace {

// Rounded to `digits` significant digits: a plot needs few, and OUT stays
// small (JSON numbers print in their shortest form).
std::vector<double> Rounded(const std::vector<double>& x, int digits) {
  std::vector<double> out;
  out.reserve(x.size());
  char buf[32];
  for (double v : x) {
    std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
    out.push_back(std::strtod(buf, nullptr));
  }
  return out;
}

// Buckets of n consecutive indices covering [0, size).
int BucketSize(std::size_t size, int max_points) {
  return std::max<int>(1, static_cast<int>((size + max_points - 1) / max_points));
}

}  // namespace

nlohmann::json ResidualPlotJson(const ResidualReport& r, int max_points) {
  nlohmann::json j;
  j["what"] = r.series_what;
  j["unit"] = r.series_unit;
  j["bench_frequencies_hz"] = {r.f1_hz, r.f2_hz};
  std::vector<const ChannelReport*> accel;  // the channels in the series' unit
  for (const ChannelReport& c : r.channels) {
    if (c.unit == r.series_unit && c.series.size() == r.t_s.size()) accel.push_back(&c);
  }
  const std::size_t n = r.t_s.size();
  if (accel.empty() || n < 4) return j;

  // Time series: per bucket two points; each channel puts its min and max
  // in the order they occurred.
  const int b = BucketSize(n, max_points);
  std::vector<double> t;
  std::vector<std::vector<double>> y(accel.size());
  for (std::size_t s = 0; s < n; s += b) {
    const std::size_t e = std::min(n, s + b);
    if (b == 1) {
      t.push_back(r.t_s[s]);
      for (std::size_t c = 0; c < accel.size(); ++c) y[c].push_back(accel[c]->series[s]);
      continue;
    }
    t.push_back(r.t_s[s]);
    t.push_back(r.t_s[e - 1]);
    for (std::size_t c = 0; c < accel.size(); ++c) {
      const auto& x = accel[c]->series;
      const auto [lo, hi] = std::minmax_element(x.begin() + s, x.begin() + e);
      y[c].push_back(lo < hi ? *lo : *hi);
      y[c].push_back(lo < hi ? *hi : *lo);
    }
  }
  j["decimation"] = b == 1 ? "none" : "min and max of every " + std::to_string(b) + " intervals";
  j["t_s"] = Rounded(t, 7);
  nlohmann::json chans = nlohmann::json::array();
  for (std::size_t c = 0; c < accel.size(); ++c) {
    chans.push_back(
        {{"name", accel[c]->name}, {"rms", accel[c]->rms}, {"values", Rounded(y[c], 4)}});
  }
  j["channels"] = chans;

  // Spectrum: periodogram without the 0-Hz bin, max per frequency bucket.
  nlohmann::json spec;
  std::vector<double> f;
  std::vector<std::vector<double>> p(accel.size());
  std::vector<Spectrum> s(accel.size());
  for (std::size_t c = 0; c < accel.size(); ++c) s[c] = Periodogram(accel[c]->series, r.dt_s);
  const std::size_t bins = s[0].freq_hz.size();
  const int fb = BucketSize(bins > 1 ? bins - 1 : 1, max_points);
  for (std::size_t k = 1; k < bins; k += fb) {
    const std::size_t e = std::min(bins, k + fb);
    std::size_t best = k;
    for (std::size_t c = 0; c < accel.size(); ++c) {
      const auto it = std::max_element(s[c].power.begin() + k, s[c].power.begin() + e);
      p[c].push_back(*it);
      if (c == 0) best = static_cast<std::size_t>(it - s[c].power.begin());
    }
    f.push_back(fb == 1 ? s[0].freq_hz[k] : s[0].freq_hz[best]);
  }
  spec["freq_hz"] = Rounded(f, 6);
  spec["unit"] = r.series_unit + "^2 (periodogram |X_k|^2 / N)";
  spec["decimation"] = fb == 1 ? "none" : "max of every " + std::to_string(fb) + " bins";
  nlohmann::json sp = nlohmann::json::array();
  for (std::size_t c = 0; c < accel.size(); ++c) {
    sp.push_back({{"name", accel[c]->name}, {"power", Rounded(p[c], 3)}});
  }
  spec["channels"] = sp;
  j["spectrum"] = spec;
  return j;
}

}  // namespace triadcal

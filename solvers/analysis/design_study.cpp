#include "solvers/analysis/design_study.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

void CheckOptions(const Scenario& s, const DesignStudyOptions& o) {
  if (!(o.static_duration_s > 0)) throw OptionError("static_duration_s", "must be > 0");
  const double longest = o.durations_s.empty() ? 0.0 : o.durations_s.back();
  if (longest * s.profile.rate_hz > static_cast<double>(kMaxSimulatedSamples)) {
    throw OptionError("durations_s", FormatDouble(longest) + " s at " +
                                         FormatDouble(s.profile.rate_hz) + " Hz is more than " +
                                         std::to_string(kMaxSimulatedSamples) + " samples");
  }
}

// The scenario's profile with another duration, and optionally periods and
// amplitudes.
HarmonicProfile ProfileOf(const Scenario& s, double duration_s) {
  HarmonicProfile p = s.profile;
  p.duration_s = duration_s;
  return p;
}

}  // namespace

DesignStudy RunDesignStudy(const Scenario& s, const ParameterLayout& layout,
                           const DesignStudyOptions& o) {
  CheckOptions(s, o);
  DesignStudy r;
  r.durations_s = o.durations_s;
  r.positions = StaticPositions(o.static_positions);
  r.design_duration_s = o.design_duration_s > 0 ? o.design_duration_s : s.profile.duration_s;
  r.static_duration_s = o.static_duration_s;
  std::vector<std::array<double, 2>> periods = o.periods_s, amplitudes = o.amplitudes_deg;
  if (periods.empty()) {
    for (double f : {0.5, 1.0, 2.0}) {
      periods.push_back({f * s.profile.period_s[0], f * s.profile.period_s[1]});
    }
  }
  if (amplitudes.empty()) {
    for (double f : {0.25, 0.5, 1.0}) {
      amplitudes.push_back(
          {f * s.profile.amplitude_rad[0] / kDegToRad, f * s.profile.amplitude_rad[1] / kDegToRad});
    }
  }
  const ObservabilityThresholds& thr = o.design.observability.thresholds;
  const double Td = r.design_duration_s;

  const std::size_t total_steps = 2 * r.durations_s.size() + periods.size() * amplitudes.size() + 3;
  std::size_t step = 0;
  auto progress = [&](const std::string& what) {
    if (o.progress) o.progress(what, static_cast<double>(step) / total_steps);
    ++step;
  };

  // 1. sigma against duration, both methods.
  for (double T : r.durations_s) {
    progress("quasi-harmonic " + FormatDouble(T) + " s");
    r.quasi_harmonic.push_back(EvaluateProfile(s, ProfileOf(s, T), layout, o.design));
    progress("static " + FormatDouble(T) + " s");
    r.static_test.push_back(EvaluateStatic(s, layout, r.positions, T, thr));
  }
  // 2. periods x amplitudes at the design duration.
  for (const auto& per : periods) {
    for (const auto& amp : amplitudes) {
      char what[64];
      std::snprintf(what, sizeof(what), "profile %g:%g s", per[0], per[1]);
      progress(what);
      HarmonicProfile p = ProfileOf(s, Td);
      for (int i = 0; i < 2; ++i) {
        p.period_s[i] = per[i];
        p.amplitude_rad[i] = amp[i] * kDegToRad;
      }
      r.grid.push_back({per, amp, EvaluateProfile(s, p, layout, o.design)});
    }
  }
  // 3. the comparison: the scenario's design against the static method.
  progress("comparison");
  r.qh_design = EvaluateProfile(s, ProfileOf(s, Td), layout, o.design);
  r.static_long = EvaluateStatic(s, layout, r.positions, r.static_duration_s, thr);
  r.static_design = EvaluateStatic(s, layout, r.positions, Td, thr);
  // 4. targets: bisection between 3 epochs (at least 1 s) and the longest duration.
  r.target_min_s = std::max(1.0, 3.0 * o.design.epoch_s);
  r.target_max_s = std::max(r.durations_s.empty() ? 0.0 : r.durations_s.back(), Td);
  for (const DesignTarget& t : o.targets) {
    progress("target " + t.key);
    const double si = t.sigma_file * layout.info(t.indices[0]).si_per_unit;
    r.targets.push_back(
        DurationForTarget(s, layout, t.indices, si, r.target_min_s, r.target_max_s, o.design));
  }
  return r;
}

double WorstSigma(const DesignPoint& d, const std::vector<int>& indices) {
  double w = 0.0;
  for (int i : indices) w = std::max(w, d.sigma[i]);
  return w;
}

bool Undetermined(const DesignPoint& d, const std::string& name) {
  return std::find(d.unobservable.begin(), d.unobservable.end(), name) != d.unobservable.end();
}

bool AnyUndetermined(const DesignPoint& d, const ParameterLayout& layout,
                     const std::vector<int>& indices) {
  const std::set<std::string> held(d.unobservable.begin(), d.unobservable.end());
  for (int i : indices) {
    if (held.count(layout.info(i).name)) return true;
  }
  return false;
}

double LogSlope(const std::vector<double>& T, const std::vector<double>& s, double t_from) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = 0; k < T.size(); ++k) {
    if (T[k] < t_from || !(s[k] > 0)) continue;  // also skips NaN (not determined)
    const double x = std::log(T[k]), y = std::log(s[k]);
    n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  if (n < 2) return std::nan("");
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace triadcal

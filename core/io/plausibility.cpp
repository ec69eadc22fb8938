// Physical bounds on the run description and the run data; the reasons are in
// docs/input-validation.md.
#include "core/io/plausibility.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "core/model/errors.h"
#include "core/model/priors.h"
#include "core/model/units.h"

namespace triadcal {

namespace {

using B = PlausibilityBounds;

// Short human number: 4 significant digits.
std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", x);
  return buf;
}

[[noreturn]] void Fail(const std::string& where, const std::string& key, const std::string& what) {
  throw InputError(where + ": " + key + ": " + what);
}

const char* kAxis[3] = {"0", "1", "2"};

void CheckBench(const RunDescription& run, const std::string& where) {
  for (int i = 0; i < 3; ++i) {
    const double mm = run.lever_arm0_m[i] / kMmToM;
    if (std::abs(mm) > B::kMaxLeverArm_mm) {
      Fail(where, std::string("bench.lever_arm_mm[") + kAxis[i] + "]",
           Num(mm) + " mm is beyond the bound |R0| <= " + Num(B::kMaxLeverArm_mm) +
               " mm (a bench platform is smaller than 2 m; is it in m or um?)");
    }
  }
  const double arcsec = run.angle_noise_rad / kArcsecToRad;
  if (arcsec > B::kMaxAngleNoise_arcsec) {
    Fail(where, "bench.angle_noise_arcsec",
         Num(arcsec) + " arcsec is beyond the bound " + Num(B::kMaxAngleNoise_arcsec) +
             " arcsec (an angle sensor worse than 1 deg cannot calibrate arcminutes)");
  }
  if (run.g_mps2 < B::kMinG_mps2 || run.g_mps2 > B::kMaxG_mps2) {
    Fail(where, "bench.g_mps2",
         Num(run.g_mps2) + " m/s^2 is outside [" + Num(B::kMinG_mps2) + ", " + Num(B::kMaxG_mps2) +
             "] (gravity on the Earth's surface; the unit is m/s^2)");
  }
}

void CheckTriad(const RunDescription& run, const std::string& where) {
  for (int i = 0; i < 3; ++i) {
    const double k = run.scale_mV_per_g[i];
    const std::string key = std::string("triad.scale_mV_per_g[") + kAxis[i] + "]";
    if (k < B::kMinScale || k > B::kMaxScale) {
      Fail(where, key,
           Num(k) + " is outside [" + Num(B::kMinScale) + ", " + Num(B::kMaxScale) +
               "] per g (no accelerometer output is outside this range)");
    }
    const double b = run.bias_mV[i];
    if (std::abs(b) > B::kMaxBiasInG * k) {
      Fail(where, std::string("triad.bias_mV[") + kAxis[i] + "]",
           Num(b) + " is " + Num(std::abs(b) / k) + " g worth of the nominal scale " + Num(k) +
               " (bound " + Num(B::kMaxBiasInG) + " g: check the units of scale and bias)");
    }
  }
  const double k_min = run.scale_mV_per_g.minCoeff();
  const double k_max = run.scale_mV_per_g.maxCoeff();
  const double n = run.noise_mV;
  if (n < B::kMinNoiseInG * k_min || n > B::kMaxNoiseInG * k_max) {
    Fail(where, "triad.noise_mV",
         Num(n) + " is outside [" + Num(B::kMinNoiseInG) + ", " + Num(B::kMaxNoiseInG) +
             "] g worth of the nominal scale (" + Num(B::kMinNoiseInG * k_min) + " to " +
             Num(B::kMaxNoiseInG * k_max) +
             "): no accelerometer is quieter than 0.1 ug per sample, and a noise of 1 g "
             "leaves nothing to calibrate");
  }
}

// Default prior sigma (SI) of every parameter of every effect.
struct DefaultScales {
  ParameterLayout layout;
  Eigen::VectorXd sigma_si;
};

DefaultScales MakeDefaultScales(const RunDescription& run) {
  std::vector<Effect> all;
  for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
  DefaultScales d{ParameterLayout(all, /*gyro=*/true), {}};
  RunDescription plain = run;
  plain.prior_sigma.clear();
  d.sigma_si = MakePrior(plain, d.layout).sigma;
  return d;
}

void CheckPriors(const RunDescription& run, const DefaultScales& d, const std::string& where) {
  for (const auto& [name, sigma] : run.prior_sigma) {
    const int i = d.layout.IndexOf(name);
    if (i < 0) continue;  // the parser reports unknown names
    const ParameterInfo& info = d.layout.info(i);
    const double def = d.sigma_si[i] / info.si_per_unit;
    if (!(def > 0.0)) continue;
    const double ratio = sigma / def;
    if (ratio < 1.0 / B::kPriorRatio || ratio > B::kPriorRatio) {
      Fail(where, "priors." + name,
           Num(sigma) + " " + info.unit + " is " + Num(ratio) + " times the default " + Num(def) +
               " " + info.unit + " (bound: between 1e-6 and 1e6 times; beyond, " +
               "the prior either fixes the parameter or adds nothing, and ruins the "
               "conditioning)");
    }
  }
}

void CheckConstraints(const RunDescription& run, const DefaultScales& d, const std::string& where) {
  for (std::size_t c = 0; c < run.constraints.size(); ++c) {
    const Constraint& con = run.constraints[c];
    double scale2 = 0.0;
    int first = -1;
    for (const auto& [name, coef] : con.terms) {
      const int i = d.layout.IndexOf(name);
      if (i < 0) continue;
      if (first < 0) first = i;
      scale2 += coef * coef * d.sigma_si[i] * d.sigma_si[i];
    }
    if (first < 0 || !(scale2 > 0.0)) continue;
    const double scale = std::sqrt(scale2);
    const ParameterInfo& info = d.layout.info(first);
    const std::string key = "constraints[" + std::to_string(c) + "] (\"" + con.expr + "\")";
    if (!std::isfinite(scale)) {
      Fail(where, key,
           "coefficients too large: the combination's prior scale overflows "
           "(bound: finite)");
    }
    if (con.sigma_si < B::kMinConstraintRatio * scale) {
      Fail(where, key,
           "sigma " + Num(con.sigma_si / info.si_per_unit) + " " + info.unit + " is " +
               Num(con.sigma_si / scale) + " of the combination's prior scale " +
               Num(scale / info.si_per_unit) + " " + info.unit +
               " (bound: at least 1e-6; tighter holds everything and ruins the conditioning)");
    }
    if (std::abs(con.value_si) > B::kMaxConstraintValue * scale) {
      Fail(where, key,
           "value " + Num(con.value_si / info.si_per_unit) + " " + info.unit + " is " +
               Num(std::abs(con.value_si) / scale) +
               " prior scales of the combination (bound 1000; check the unit suffix)");
    }
  }
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

void CheckDescriptionPlausible(const RunDescription& run, const std::string& where) {
  CheckBench(run, where);
  CheckTriad(run, where);
  const DefaultScales d = MakeDefaultScales(run);
  CheckPriors(run, d, where);
  CheckConstraints(run, d, where);
}

void CheckSamplesPlausible(const DataTable& table, const ChannelSet& c,
                           const double (&nominal_scale)[3], const double (&nominal_bias)[3]) {
  const std::vector<double>& t = c.t->values;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (std::abs(t[k]) > B::kMaxAbsTime_s) {
      throw InputError(table.Where(k) + ": " + c.t->label + ": " + Num(t[k]) +
                       " s is beyond the bound |t| <= " + Num(B::kMaxAbsTime_s) +
                       " s (3000 years)");
    }
  }
  if (t.size() >= 2) {
    const double span = t.back() - t.front();
    if (span > B::kMaxSpan_s) {
      throw InputError(table.path + ": " + c.t->label + ": the run spans " + Num(span) +
                       " s, beyond the bound " + Num(B::kMaxSpan_s) +
                       " s (11.6 days): is the time in ms? set columns.t.unit: ms");
    }
    std::vector<double> dt(t.size() - 1);
    for (std::size_t k = 1; k < t.size(); ++k) dt[k - 1] = t[k] - t[k - 1];
    const double median = Median(std::move(dt));  // dt is not read again
    if (median > B::kMaxMedianInterval_s) {
      throw InputError(table.path + ": " + c.t->label + ": median sample interval " + Num(median) +
                       " s is beyond the bound " + Num(B::kMaxMedianInterval_s) +
                       " s (the bench swings with periods of seconds): is the time in ms? "
                       "set columns.t.unit: ms");
    }
    if (median < B::kMinMedianInterval_s) {
      throw InputError(table.path + ": " + c.t->label + ": median sample interval " + Num(median) +
                       " s is below the bound " + Num(B::kMinMedianInterval_s) +
                       " s (50 kHz): is the time in us, or in s declared as ms?");
    }
  }
  for (const ChannelValues* l : c.lambda) {
    for (std::size_t k = 0; k < l->values.size(); ++k) {
      if (std::abs(l->values[k]) > B::kMaxAbsAngle_deg) {
        throw InputError(table.Where(k) + ": " + l->label + ": " + Num(l->values[k]) +
                         " deg is beyond the bound |angle| <= " + Num(B::kMaxAbsAngle_deg) +
                         " deg");
      }
    }
  }
  for (const ChannelValues* r : c.rate) {
    for (std::size_t k = 0; k < r->values.size(); ++k) {
      if (std::abs(r->values[k]) > B::kMaxRate_deg_s) {
        throw InputError(table.Where(k) + ": " + r->label + ": " + Num(r->values[k]) +
                         " deg/s is beyond the bound " + Num(B::kMaxRate_deg_s) +
                         " deg/s (10 turns per second; is it in rad/s or in deg/min?)");
      }
    }
  }
  for (int i = 0; i < 3; ++i) {
    const ChannelValues& w = *c.w[i];
    const double bound = B::kMaxReadingInG * nominal_scale[i];
    for (std::size_t k = 0; k < w.values.size(); ++k) {
      if (std::abs(w.values[k] - nominal_bias[i]) > bound) {
        throw InputError(table.Where(k) + ": " + w.label + ": " + Num(w.values[k]) + " is " +
                         Num(std::abs(w.values[k] - nominal_bias[i]) / nominal_scale[i]) +
                         " g from the nominal bias at the nominal scale " + Num(nominal_scale[i]) +
                         " per g (bound " + Num(B::kMaxReadingInG) + " g): check columns." +
                         w.name + ".unit and triad.scale_mV_per_g");
      }
    }
  }
}

void CheckAngleRates(const DataTable& table, const ChannelValues& t,
                     const ChannelValues (&lambda)[2]) {
  const std::vector<double>& ts = t.values;
  for (const ChannelValues& l : lambda) {
    const std::vector<double>& v = l.values;
    for (std::size_t k = 1; k < v.size() && k < ts.size(); ++k) {
      const double step = std::abs(v[k] - v[k - 1]);
      const double dt = ts[k] - ts[k - 1];
      if (step > 1.0 && step > B::kMaxRate_deg_s * dt) {
        throw InputError(table.Where(k) + ": " + l.label + ": jumps by " + Num(step) + " deg in " +
                         Num(dt) + " s, beyond the bound " + Num(B::kMaxRate_deg_s) +
                         " deg/s (10 turns per second): a wild angle, or the time unit is "
                         "wrong");
      }
    }
  }
}

void CheckAnglesNotRadiansWindowed(const DataTable& table, const ChannelValues (&lambda)[2],
                                   const ChannelValues (&w)[3], const double (&nominal_scale)[3],
                                   double nominal_noise) {
  constexpr double kWindowPath_deg = 6.0;
  const std::size_t n = lambda[0].values.size();
  if (lambda[1].values.size() != n) return;
  for (const ChannelValues& c : w) {
    if (c.values.size() != n) return;
  }
  double noise_g = 0.0;
  for (double k : nominal_scale) noise_g = std::max(noise_g, nominal_noise / k);
  const double threshold_g = 0.5 + 6.0 * noise_g;
  std::size_t windows = 0, swinging = 0;
  double path = 0.0;
  double lo[3], hi[3];
  auto reset = [&](std::size_t k) {
    path = 0.0;
    for (int i = 0; i < 3; ++i) lo[i] = hi[i] = w[i].values[k];
  };
  if (n == 0) return;
  reset(0);
  for (std::size_t k = 1; k < n; ++k) {
    path += std::abs(lambda[0].values[k] - lambda[0].values[k - 1]) +
            std::abs(lambda[1].values[k] - lambda[1].values[k - 1]);
    double swing_g = 0.0;
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], w[i].values[k]);
      hi[i] = std::max(hi[i], w[i].values[k]);
      swing_g = std::max(swing_g, (hi[i] - lo[i]) / nominal_scale[i]);
    }
    if (path >= kWindowPath_deg) {
      ++windows;
      if (swing_g > threshold_g) ++swinging;
      reset(k);
    }
  }
  if (windows >= 3 && 2 * swinging > windows) {
    throw InputError(table.path + ": " + lambda[0].label + ", " + lambda[1].label + ": in " +
                     std::to_string(swinging) + " of " + std::to_string(windows) +
                     " stretches where the angles move by 6 deg the readings swing by more "
                     "than " +
                     Num(threshold_g) +
                     " g (gravity can turn by only 0.1 g there): the angles look like "
                     "radians, not degrees; set columns.lambda1.unit and "
                     "columns.lambda2.unit to rad");
  }
}

void CheckGyroUnits(const DataTable& table, const ChannelValues& t,
                    const ChannelValues (&lambda)[2], const ChannelValues (&g)[3],
                    const std::string& declared_unit, double nominal_scale) {
  const std::vector<double>& ts = t.values;
  const std::size_t n = ts.size();
  if (lambda[0].values.size() != n || lambda[1].values.size() != n) return;
  for (const ChannelValues& c : g) {
    if (c.values.size() != n) return;
  }
  // Windows of at least kWindow_s (one sample interval when that is longer),
  // each weighted by its length; a window across a gap is left out.
  double bench_ss = 0.0, gyro_ss = 0.0, span_s = 0.0;
  std::size_t windows = 0;
  for (std::size_t k = 0; k + 1 < n;) {
    std::size_t j = k + 1;
    while (j + 1 < n && ts[j] - ts[k] < B::kGyroWindow_s) ++j;
    const double dt = ts[j] - ts[k];
    if (dt > 0.0 && dt <= B::kGyroMaxWindow_s) {
      const double d1 = lambda[0].values[j] - lambda[0].values[k];
      const double d2 = lambda[1].values[j] - lambda[1].values[k];
      double g2 = 0.0;
      for (std::size_t m = k; m < j; ++m) {
        for (const ChannelValues& c : g) g2 += c.values[m] * c.values[m];
      }
      bench_ss += (d1 * d1 + d2 * d2) / dt;  // (rate^2) * dt
      gyro_ss += g2 / static_cast<double>(j - k) * dt;
      span_s += dt;
      ++windows;
    }
    k = j;
  }
  if (windows < 3 || !(span_s > 0.0)) return;
  const double bench_rms = std::sqrt(bench_ss / span_s);
  const double gyro_rms = std::sqrt(gyro_ss / span_s);
  if (!(bench_rms > B::kGyroMinBenchRate_deg_s)) return;  // too still to judge by
  const double ratio = gyro_rms / (bench_rms * std::abs(nominal_scale));
  const double per_rad = 1.0 / kDegToRad;  // 57.3
  const std::string labels = g[0].label + ", " + g[1].label + ", " + g[2].label;
  const std::string measured =
      "the RMS of |g| over the run is " + Num(gyro_rms) + " deg/s as declared, " + Num(ratio) +
      " times the bench's angle rate (RMS " + Num(bench_rms) +
      " deg/s from lambda1, lambda2) at the nominal scale " + Num(nominal_scale);
  const double f = B::kGyroUnitFactorTolerance;
  if (declared_unit == "deg/s" && ratio > 1.0 / (per_rad * f) && ratio < f / per_rad) {
    throw InputError(table.path + ": " + labels + ": " + measured +
                     ": the gyro readings look like rad/s, not deg/s; declare `unit: rad/s` "
                     "(columns.gx, gy, gz)");
  }
  if (declared_unit == "rad/s" && ratio > per_rad / f && ratio < per_rad * f) {
    throw InputError(table.path + ": " + labels + ": " + measured +
                     ": the gyro readings look like deg/s declared as rad/s; declare `unit: "
                     "deg/s` (columns.gx, gy, gz)");
  }
  if (ratio < 1.0 / B::kGyroMaxRatio || ratio > B::kGyroMaxRatio) {
    throw InputError(table.path + ": " + labels + ": " + measured + " (bound: within a factor " +
                     Num(B::kGyroMaxRatio) +
                     "): check the gyro's unit (columns.gx, gy, gz: deg/s, rad/s or counts with "
                     "counts_per_dps) and gyro.scale");
  }
}

std::vector<std::string> CheckConstantChannels(const DataTable& table,
                                               const ChannelValues (&lambda)[2],
                                               const bool (&lambda_from_file)[2],
                                               const ChannelValues (&w)[3],
                                               const bool (&w_from_file)[3]) {
  auto constant = [](const ChannelValues& c) {
    return !c.values.empty() && std::all_of(c.values.begin(), c.values.end(),
                                            [&](double v) { return v == c.values[0]; });
  };
  auto span = [](const ChannelValues& c) {
    if (c.values.empty()) return 0.0;
    const auto [lo, hi] = std::minmax_element(c.values.begin(), c.values.end());
    return *hi - *lo;
  };
  std::vector<std::string> warnings;
  const bool still[2] = {constant(lambda[0]), constant(lambda[1])};
  if (lambda_from_file[0] && lambda_from_file[1] && still[0] && still[1]) {
    throw InputError(table.path + ": " + lambda[0].label + ", " + lambda[1].label +
                     ": both angles are constant (" + Num(lambda[0].values[0]) + " and " +
                     Num(lambda[1].values[0]) +
                     " deg) in every sample: no bench motion was recorded (for a run without a "
                     "bench declare them with columns.lambda1: {value: 0}, lambda2: {value: 0})");
  }
  for (int i = 0; i < 2; ++i) {
    if (lambda_from_file[i] && still[i] && !still[1 - i]) {
      warnings.push_back(lambda[i].label + " is constant (" + Num(lambda[i].values[0]) +
                         " deg) in every sample: no motion about the " +
                         (i == 0 ? "outer" : "inner") +
                         " axis (a single-axis rig declares it with {value: ...})");
    }
  }
  const bool moving = span(lambda[0]) > 10.0 || span(lambda[1]) > 10.0;
  for (int i = 0; i < 3; ++i) {
    if (!w_from_file[i] || !constant(w[i])) continue;
    warnings.push_back(w[i].label + ": every sample is " + Num(w[i].values[0]) +
                       (moving ? " while the bench turns: a dead channel or a damaged file"
                               : ": a dead channel, or a bench that never moved"));
  }
  return warnings;
}

}  // namespace triadcal
